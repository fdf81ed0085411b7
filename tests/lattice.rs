//! Lattice builders (cube/jelly and cloth) against independent truths: brute-force neighbour
//! searches, closed-form spring counts, geometry, and the SHA-256 of docs/workloads.md's canonical
//! set-up bytes.

use std::collections::HashSet;

use glam::DVec3;
use sha2::{Digest, Sha256};
use springlab::scene::builder::Builder;
use springlab::scene::lattice::{
    ClothSpec, CubeSpec, KindCoefficients, cloth, corners, count_kinds, course_body_offset,
    course_rotation_axis, cube, setup_bytes,
};
use springlab::{SceneError, Spring, SpringKind};

/// An unordered pair with its kind.
type Edge = (u32, u32, SpringKind);

fn edges(springs: &[Spring]) -> Vec<Edge> {
    springs
        .iter()
        .map(|s| (s.a.min(s.b), s.a.max(s.b), s.kind))
        .collect()
}

/// Classifies a lattice displacement by brute force: struct = one axis step of 1, shear = every
/// component in {-1, 0, 1} with at least two non-zero, bend = one axis step of 2.
fn classify(d: &[i64]) -> Option<SpringKind> {
    let nonzero = d.iter().filter(|&&c| c != 0).count();
    let max = d.iter().map(|c| c.abs()).max().unwrap_or(0);
    match (nonzero, max) {
        (1, 1) => Some(SpringKind::Struct),
        (n, 1) if n >= 2 => Some(SpringKind::Shear),
        (1, 2) => Some(SpringKind::Bend),
        _ => None,
    }
}

/// Every pair of particles of an `nx × ny × nz` lattice (index `ix + nx (iy + ny iz)`), classified.
fn brute_force_cube(counts: [usize; 3]) -> HashSet<Edge> {
    let [nx, ny, nz] = counts;
    let coord = |p: usize| {
        [
            (p % nx) as i64,
            ((p / nx) % ny) as i64,
            (p / (nx * ny)) as i64,
        ]
    };
    let total = nx * ny * nz;
    let mut set = HashSet::new();
    for p in 0..total {
        for q in p + 1..total {
            let (a, b) = (coord(p), coord(q));
            let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            if let Some(kind) = classify(&d) {
                set.insert((p as u32, q as u32, kind));
            }
        }
    }
    set
}

/// Every pair of particles of an `n × n` grid (index `r n + c`), classified.
fn brute_force_cloth(n: usize) -> HashSet<Edge> {
    let mut set = HashSet::new();
    for p in 0..n * n {
        for q in p + 1..n * n {
            let d = [
                (q / n) as i64 - (p / n) as i64,
                (q % n) as i64 - (p % n) as i64,
            ];
            if let Some(kind) = classify(&d) {
                set.insert((p as u32, q as u32, kind));
            }
        }
    }
    set
}

fn build_cube(spec: &CubeSpec) -> Builder {
    let mut b = Builder::new();
    assert_eq!(cube(&mut b, spec), 0);
    b
}

fn build_cloth(spec: &ClothSpec) -> Builder {
    let mut b = Builder::new();
    assert_eq!(cloth(&mut b, spec), 0);
    b
}

/// The springs as a set, asserting there is no duplicate (in either orientation or kind).
fn edge_set(springs: &[Spring]) -> HashSet<Edge> {
    let list = edges(springs);
    let set: HashSet<Edge> = list.iter().copied().collect();
    assert_eq!(set.len(), list.len(), "duplicate springs");
    let pairs: HashSet<(u32, u32)> = list.iter().map(|&(a, b, _)| (a, b)).collect();
    assert_eq!(pairs.len(), list.len(), "a pair joined by two springs");
    set
}

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn cube_spec(counts: [usize; 3], edge: DVec3) -> CubeSpec {
    CubeSpec {
        counts,
        edge_length: edge,
        offset: DVec3::new(0.3, -1.2, 2.5),
        ..CubeSpec::default()
    }
}

#[test]
fn cube_10_counts_and_pairs_match_brute_force() {
    let b = build_cube(&CubeSpec::default());
    assert_eq!(b.len(), 1000);
    assert_eq!(count_kinds(&b.springs), [2700, 7776, 2400]);
    assert_eq!(b.springs.len(), 12_876);
    // Face diagonals 4 860, body diagonals 2 916 (docs/course.md §2).
    let body = b
        .springs
        .iter()
        .filter(|s| s.kind == SpringKind::Shear)
        .filter(|s| {
            let d = b.x[s.b as usize] - b.x[s.a as usize];
            d.x != 0.0 && d.y != 0.0 && d.z != 0.0
        })
        .count();
    assert_eq!(body, 2916);
    assert_eq!(edge_set(&b.springs), brute_force_cube([10, 10, 10]));
}

#[test]
fn non_cubic_cube_matches_brute_force() {
    let spec = cube_spec([3, 4, 5], DVec3::new(0.6, 1.5, 2.0));
    let b = build_cube(&spec);
    assert_eq!(b.len(), 60);
    // Closed forms of the module documentation for (nx, ny, nz) = (3, 4, 5).
    let (nx, ny, nz) = (3, 4, 5);
    let structs = (nx - 1) * ny * nz + nx * (ny - 1) * nz + nx * ny * (nz - 1);
    let shear = 2 * (nx - 1) * (ny - 1) * nz
        + 2 * (nx - 1) * ny * (nz - 1)
        + 2 * nx * (ny - 1) * (nz - 1)
        + 4 * (nx - 1) * (ny - 1) * (nz - 1);
    let bend = (nx - 2) * ny * nz + nx * (ny - 2) * nz + nx * ny * (nz - 2);
    assert_eq!(count_kinds(&b.springs), [structs, shear, bend]);
    assert_eq!(edge_set(&b.springs), brute_force_cube([3, 4, 5]));
}

#[test]
fn cube_springs_come_kind_by_kind_particle_by_particle() {
    let b = build_cube(&cube_spec([3, 4, 5], DVec3::ONE));
    let kinds: Vec<SpringKind> = b.springs.iter().map(|s| s.kind).collect();
    let mut sorted = kinds.clone();
    sorted.sort();
    assert_eq!(kinds, sorted, "struct, then shear, then bend");
    for kind in SpringKind::ALL {
        let of_kind: Vec<&Spring> = b.springs.iter().filter(|s| s.kind == kind).collect();
        assert!(of_kind.windows(2).all(|w| w[0].a <= w[1].a));
        // Each from its first end a, along a stencil offset whose first non-zero step is +1 or +2.
        let coord = |p: u32| [(p % 3) as i64, ((p / 3) % 4) as i64, (p / 12) as i64];
        for s in of_kind {
            let (a, b) = (coord(s.a), coord(s.b));
            let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            assert!(d.iter().find(|&&c| c != 0).is_some_and(|&c| c > 0), "{s:?}");
        }
    }
}

#[test]
fn cube_kinds_select_what_is_built() {
    let mut spec = cube_spec([4, 4, 4], DVec3::ONE);
    spec.kinds = vec![SpringKind::Bend, SpringKind::Struct, SpringKind::Struct];
    let b = build_cube(&spec);
    let [s, sh, bd] = count_kinds(&b.springs);
    assert_eq!((s, sh, bd), (3 * 3 * 16, 0, 3 * 2 * 16));
    // Struct first even though bend was listed first.
    assert_eq!(b.springs[0].kind, SpringKind::Struct);
    spec.kinds.clear();
    assert!(build_cube(&spec).springs.is_empty());
}

#[test]
fn cube_coefficients_per_kind() {
    let mut spec = cube_spec([3, 3, 3], DVec3::ONE);
    spec.coefficients = KindCoefficients {
        struct_: (1.0, 2.0),
        shear: (3.0, 4.0),
        bend: (5.0, 6.0),
    };
    for s in build_cube(&spec).springs {
        let expected = match s.kind {
            SpringKind::Struct => (1.0, 2.0),
            SpringKind::Shear => (3.0, 4.0),
            SpringKind::Bend => (5.0, 6.0),
        };
        assert_eq!((s.stiffness, s.damping), expected);
    }
    assert_eq!(
        KindCoefficients::default(),
        KindCoefficients::uniform(2000.0, 60.0)
    );
}

#[test]
fn cloth_25_counts_and_pairs_match_brute_force() {
    let spec = ClothSpec::course_2022();
    let b = build_cloth(&spec);
    assert_eq!(b.len(), 625);
    assert_eq!(count_kinds(&b.springs), [1200, 1152, 1150]);
    assert_eq!(edge_set(&b.springs), brute_force_cloth(25));
    // x, z ∈ [-2, 2] at y = 0.
    assert_eq!(b.x[0], DVec3::new(-2.0, 0.0, -2.0));
    assert!((b.x[624] - DVec3::new(2.0, 0.0, 2.0)).length() < 1e-12);
}

#[test]
fn cloth_counts_follow_the_closed_forms() {
    for n in [2, 3, 7, 64] {
        let b = build_cloth(&ClothSpec::w2_cloth(n));
        assert_eq!(
            count_kinds(&b.springs),
            [2 * n * (n - 1), 2 * (n - 1) * (n - 1), 2 * n * (n - 2)],
            "n = {n}"
        );
    }
    let b = build_cloth(&ClothSpec::w2_cloth(64));
    assert_eq!(count_kinds(&b.springs), [8064, 7938, 7936]);
    assert_eq!(
        edge_set(&build_cloth(&ClothSpec::w2_cloth(7)).springs),
        brute_force_cloth(7)
    );
}

#[test]
fn cloth_corners_are_pinned() {
    let spec = ClothSpec::course_2024();
    assert_eq!(spec.pinned, vec![0, 24, 600, 624]);
    let (model, state) = build_cloth(&spec).build(DVec3::new(0.0, -9.8, 0.0), 0.0);
    for p in 0..625 {
        let corner = [0, 24, 600, 624].contains(&p);
        assert_eq!(model.inv_mass[p] == 0.0, corner, "particle {p}");
        if !corner {
            assert_eq!(model.inv_mass[p], 1.0);
        }
    }
    assert_eq!(state.x[0].y, 1.0);
    assert_eq!(corners(1), vec![0]);
    assert!(corners(0).is_empty());
    assert_eq!(corners(2), vec![0, 1, 2, 3]);
}

#[test]
fn rest_lengths_are_initial_distances_and_lattice_lengths() {
    // Different spacing per axis, so every neighbour kind has its own length.
    let edge = DVec3::new(0.6, 1.5, 2.8);
    let spec = cube_spec([3, 4, 5], edge);
    let h = DVec3::new(0.6 / 2.0, 1.5 / 3.0, 2.8 / 4.0);
    assert_eq!(spec.spacing(), h);
    let b = build_cube(&spec);
    for s in &b.springs {
        let d = b.x[s.b as usize] - b.x[s.a as usize];
        assert_eq!(s.rest_length, (d.x * d.x + d.y * d.y + d.z * d.z).sqrt());
        // The lattice step (dx, dy, dz) of this spring, from the particle indices.
        let coord = |p: u32| {
            let p = p as i64;
            DVec3::new((p % 3) as f64, ((p / 3) % 4) as f64, (p / 12) as f64)
        };
        let step = coord(s.b) - coord(s.a);
        let expected = (step * h).length();
        assert!((s.rest_length - expected).abs() < 1e-12, "{s:?}");
    }
    // The far corner is one edge length from the first.
    assert!((b.x[59] - b.x[0] - edge).length() < 1e-12);
    assert_eq!(b.x[0], spec.offset);

    let cloth_spec = ClothSpec {
        n: 5,
        size: [2.0, 3.0],
        pinned: corners(5),
        ..ClothSpec::course_2022()
    };
    let b = build_cloth(&cloth_spec);
    assert_eq!(cloth_spec.spacing(), [0.5, 0.75]);
    for s in &b.springs {
        let d = b.x[s.b as usize] - b.x[s.a as usize];
        assert_eq!(s.rest_length, (d.x * d.x + d.y * d.y + d.z * d.z).sqrt());
        assert_eq!(d.y, 0.0);
    }
    assert_eq!(b.x[24] - b.x[0], DVec3::new(2.0, 0.0, 3.0));
}

#[test]
fn rotated_cube_is_a_rigid_rotation_about_the_centre() {
    let plain = cube_spec([4, 5, 6], DVec3::new(1.0, 2.0, 3.0));
    let rotated = CubeSpec {
        rotation: Some((DVec3::new(1.0, 0.0, 1.0), 0.7)),
        ..plain.clone()
    };
    let (a, b) = (build_cube(&plain), build_cube(&rotated));
    assert_eq!(a.springs.len(), b.springs.len());
    for (s, t) in a.springs.iter().zip(&b.springs) {
        assert_eq!((s.a, s.b, s.kind), (t.a, t.b, t.kind));
        assert!((s.rest_length - t.rest_length).abs() < 1e-12);
    }
    let centroid = |x: &[DVec3]| x.iter().sum::<DVec3>() / x.len() as f64;
    let centre = plain.offset + DVec3::new(0.5, 1.0, 1.5);
    assert!((centroid(&a.x) - centre).length() < 1e-12);
    assert!((centroid(&b.x) - centre).length() < 1e-12);
    // Something did move: the corner is no longer at the offset, but at the same distance from
    // the centre; the axis (1, 0, 1) through the centre is fixed.
    assert!((b.x[0] - a.x[0]).length() > 0.1);
    assert!(((b.x[0] - centre).length() - (a.x[0] - centre).length()).abs() < 1e-12);
    let axis = course_rotation_axis();
    assert!((axis - DVec3::new(1.0, 0.0, 1.0) / 2f64.sqrt()).length() < 1e-15);
    let probe = centre + axis * 0.3;
    let q = glam::DQuat::from_axis_angle(axis, 0.7);
    assert!((centre + q * (probe - centre) - probe).length() < 1e-12);
}

#[test]
fn several_bodies_in_one_builder() {
    let l = 4.0;
    let base = DVec3::new(0.0, 5.0, 0.0);
    assert_eq!(course_body_offset(0, l, base), DVec3::new(0.0, 9.0, 0.0));
    assert_eq!(course_body_offset(2, l, base), DVec3::new(0.0, 9.0, -16.0));
    let mut b = Builder::new();
    let mut firsts = Vec::new();
    for index in 0..2 {
        let spec = CubeSpec {
            counts: [3, 3, 3],
            offset: course_body_offset(index, l, base),
            ..CubeSpec::default()
        };
        firsts.push(cube(&mut b, &spec));
    }
    assert_eq!(firsts, vec![0, 27]);
    let half = b.springs.len() / 2;
    for (s, t) in b.springs[..half].iter().zip(&b.springs[half..]) {
        assert_eq!((s.a + 27, s.b + 27), (t.a, t.b));
        assert_eq!(s.rest_length, t.rest_length);
    }
    // The second body is 2 L further along -z, never overlapping the first.
    assert_eq!(b.x[27] - b.x[0], DVec3::new(0.0, 0.0, -8.0));
    let first = cloth(&mut b, &ClothSpec::w2_cloth(3));
    assert_eq!(first, 54);
    assert!(b.pinned[54] && b.pinned[56] && !b.pinned[55]);
    assert!(b.springs.iter().all(|s| s.a < 63 && s.b < 63));
}

#[test]
fn w1_jelly_setup_bytes_match_workloads() {
    let spec = CubeSpec::w1_jelly();
    assert_eq!(spec.spacing(), DVec3::splat(0.1));
    let b = build_cube(&spec);
    // W1's positions, written out as docs/workloads.md states them.
    for (p, x) in b.x.iter().enumerate() {
        let (ix, iy, iz) = (p % 10, (p / 10) % 10, p / 100);
        let w1 = DVec3::new(ix as f64 * 0.1, 1.0 + iy as f64 * 0.1, iz as f64 * 0.1);
        assert_eq!(*x, w1);
    }
    assert_eq!(
        sha256_hex(&setup_bytes(&b.x, &b.springs)),
        "2998d5d89a68a2ffbb5b5399c5283fdbcb11588749f46363c236cc5aa00d4e96"
    );
}

#[test]
fn w2_cloth_setup_bytes_match_workloads() {
    for (n, hash, springs) in [
        (
            64,
            "0f03a18dc799873f3fb6f40d89f011bafbaa56dd86009e9afeaad69ce60e43cb",
            23_938,
        ),
        (
            128,
            "d42f10ae2054dfcf1d700d982f4d83a108e5d3c0cca1e5fbe71a76d66d05104a",
            97_026,
        ),
    ] {
        let spec = ClothSpec::w2_cloth(n);
        let b = build_cloth(&spec);
        assert_eq!(b.springs.len(), springs);
        let h = 1.0 / (n - 1) as f64;
        for (p, x) in b.x.iter().enumerate() {
            let (r, c) = (p / n, p % n);
            assert_eq!(*x, DVec3::new(c as f64 * h, 1.0, r as f64 * h));
        }
        let pinned: Vec<usize> = (0..n * n).filter(|&p| b.pinned[p]).collect();
        assert_eq!(pinned, vec![0, n - 1]);
        assert_eq!(sha256_hex(&setup_bytes(&b.x, &b.springs)), hash, "cloth{n}");
    }
}

#[test]
fn setup_bytes_layout() {
    let x = [DVec3::new(1.0, 2.0, 3.0), DVec3::new(-0.5, 0.0, 4.0)];
    let springs = [Spring {
        a: 0,
        b: 1,
        rest_length: 2.5,
        stiffness: 1.0,
        damping: 0.0,
        kind: SpringKind::Struct,
    }];
    let bytes = setup_bytes(&x, &springs);
    assert_eq!(bytes.len(), 2 * 24 + 16);
    assert_eq!(&bytes[0..8], &1.0f64.to_le_bytes());
    assert_eq!(&bytes[40..48], &4.0f64.to_le_bytes());
    assert_eq!(&bytes[48..52], &[0, 0, 0, 0]);
    assert_eq!(&bytes[52..56], &[1, 0, 0, 0]);
    assert_eq!(&bytes[56..64], &2.5f64.to_le_bytes());
}

fn message(result: Result<(), SceneError>) -> String {
    result.expect_err("must be rejected").to_string()
}

#[test]
fn bad_cube_specs_are_rejected_with_a_message() {
    let ok = CubeSpec::default();
    assert!(ok.validate().is_ok());
    let m = message(
        CubeSpec {
            counts: [10, 1, 10],
            ..ok.clone()
        }
        .validate(),
    );
    assert_eq!(m, "the cube needs at least 2 particles along y, got 1");
    let m = message(
        CubeSpec {
            counts: [usize::MAX, 2, 2],
            ..ok.clone()
        }
        .validate(),
    );
    assert!(m.contains("too many particles"), "{m}");
    let m = message(
        CubeSpec {
            edge_length: DVec3::new(1.0, 1.0, -1.0),
            ..ok.clone()
        }
        .validate(),
    );
    assert_eq!(
        m,
        "the cube's edge length along z must be a finite number > 0 m, got -1"
    );
    let m = message(
        CubeSpec {
            mass: 0.0,
            ..ok.clone()
        }
        .validate(),
    );
    assert_eq!(m, "the particle mass must be a finite number > 0 kg, got 0");
    let m = message(
        CubeSpec {
            coefficients: KindCoefficients {
                shear: (f64::NAN, 1.0),
                ..KindCoefficients::default()
            },
            ..ok.clone()
        }
        .validate(),
    );
    assert_eq!(
        m,
        "shear stiffness must be a finite number >= 0 N/m, got NaN"
    );
    let m = message(
        CubeSpec {
            coefficients: KindCoefficients {
                bend: (1.0, -2.0),
                ..KindCoefficients::default()
            },
            ..ok.clone()
        }
        .validate(),
    );
    assert_eq!(m, "bend damping must be a finite number >= 0 N·s/m, got -2");
    let m = message(
        CubeSpec {
            rotation: Some((DVec3::ZERO, 1.0)),
            ..ok.clone()
        }
        .validate(),
    );
    assert!(
        m.starts_with("the rotation axis must be a finite, non-zero vector"),
        "{m}"
    );
    let m = message(
        CubeSpec {
            offset: DVec3::new(0.0, f64::INFINITY, 0.0),
            ..ok
        }
        .validate(),
    );
    assert!(m.starts_with("the cube's offset must be finite"), "{m}");
}

#[test]
fn bad_cloth_specs_are_rejected_with_a_message() {
    let ok = ClothSpec::default();
    assert!(ok.validate().is_ok());
    let m = message(ClothSpec { n: 1, ..ok.clone() }.validate());
    assert_eq!(m, "the cloth needs at least 2 particles per side, got 1");
    let m = message(
        ClothSpec {
            pinned: vec![0, 625],
            ..ok.clone()
        }
        .validate(),
    );
    assert_eq!(
        m,
        "pinned particle 625 is out of range: the cloth has particles 0..=624"
    );
    let m = message(
        ClothSpec {
            size: [4.0, 0.0],
            ..ok.clone()
        }
        .validate(),
    );
    assert_eq!(
        m,
        "the cloth's size along z must be a finite number > 0 m, got 0"
    );
    let m = message(ClothSpec { n: 1 << 17, ..ok }.validate());
    assert!(m.contains("too many particles"), "{m}");
}

#[test]
#[should_panic(expected = "invalid cloth: the cloth needs at least 2 particles per side, got 0")]
fn cloth_builder_asserts_its_preconditions() {
    cloth(
        &mut Builder::new(),
        &ClothSpec {
            n: 0,
            ..ClothSpec::default()
        },
    );
}
