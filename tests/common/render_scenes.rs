//! Course-like scenes for the render tests and bench, built from the lattice builders and the
//! collider constructors (independent of which built-in scenes exist).
#![allow(dead_code)]

use glam::DVec3;
use springlab::physics::collide::{Collider, ContactParams, DynamicSphere};
use springlab::physics::{Method, MethodParams};
use springlab::scene::builder::Builder;
use springlab::scene::lattice::{ClothSpec, CubeSpec, KindCoefficients, cloth, cube};
use springlab::scene::{Body, Scene};

/// NYCU 2023 `jelly-bowl`: a 10 × 10 × 10 jelly (edge 4 m, 1 kg particles, K = 2000 N/m,
/// D = 60 N·s/m) above the floor with a hole and the bowl under it, dt = 1 ms.
pub fn jelly_bowl() -> Scene {
    jelly_bowl_sized(10)
}

/// [`jelly_bowl`] with `n³` particles.
pub fn jelly_bowl_sized(n: usize) -> Scene {
    let spec = CubeSpec {
        counts: [n; 3],
        edge_length: DVec3::splat(4.0),
        mass: 1.0,
        coefficients: KindCoefficients::uniform(2000.0, 60.0),
        offset: DVec3::new(-4.8, 11.0, 0.0),
        rotation: None,
        ..CubeSpec::default()
    };
    let mut b = Builder::new();
    cube(&mut b, &spec);
    let (model, state) = b.build(DVec3::new(0.0, -9.8, 0.0), 0.0);
    Scene {
        name: "jelly-bowl-like".into(),
        bodies: vec![Body {
            label: "jelly".into(),
            model: model.with_colliders(
                Collider::course_2023_terrain(),
                ContactParams::course_2023(),
            ),
            state,
            method: Method::SemiImplicitEuler,
            params: MethodParams::default(),
        }],
        dt: 0.001,
        duration: 5.0,
    }
}

/// NYCU 2022 `cloth-spheres`: a 25 × 25 cloth pinned at its corners and four spheres of radius
/// 0.5 m, 1 m above it, dt = 0.1 ms.
pub fn cloth_spheres() -> Scene {
    let mut b = Builder::new();
    cloth(&mut b, &ClothSpec::course_2022());
    let (model, state) = b.build(DVec3::new(0.0, -9.8, 0.0), 0.0);
    let spheres = [(-0.75, -0.75), (0.75, -0.75), (-0.75, 0.75), (0.75, 0.75)]
        .map(|(x, z)| DynamicSphere::new(DVec3::new(x, 1.0, z), 0.5))
        .to_vec();
    Scene {
        name: "cloth-spheres-like".into(),
        bodies: vec![Body {
            label: "cloth".into(),
            model: model.with_colliders(Vec::new(), ContactParams::course_2021()),
            state: state.with_spheres(spheres),
            method: Method::SemiImplicitEuler,
            params: MethodParams::default(),
        }],
        dt: 1e-4,
        duration: 3.0,
    }
}

/// A cloth draped over a sphere of radius 1 m at the origin, made by formula, not simulation:
/// 25 × 25 particles over x, z ∈ [-2, 2] m lying on the sphere's cap and falling off it along
/// a smooth curve, with a ripple so the shading varies. Only the geometry matters.
pub fn draped_cloth() -> Scene {
    let mut b = Builder::new();
    cloth(&mut b, &ClothSpec::course_2024());
    let (model, mut state) = b.build(DVec3::new(0.0, -9.8, 0.0), 0.0);
    let r: f64 = 1.0;
    // On the cap up to ρ0 = 0.75 r, then falling at slope 1.05 while drawing in, with folds.
    let rho0 = 0.75 * r;
    let y0 = (r * r - rho0 * rho0).sqrt() + 0.03;
    for p in &mut state.x {
        let rho = (p.x * p.x + p.z * p.z).sqrt();
        let phi = p.z.atan2(p.x);
        *p = if rho <= rho0 {
            DVec3::new(p.x, (r * r - rho * rho).sqrt() + 0.03, p.z)
        } else {
            let d = rho - rho0;
            let radial = rho0 + 0.45 * d + 0.08 * d * (6.0 * phi).sin();
            DVec3::new(radial * phi.cos(), y0 - 1.05 * d, radial * phi.sin())
        };
    }
    state.spheres = vec![DynamicSphere::kinematic(DVec3::ZERO, r, DVec3::ZERO)];
    Scene {
        name: "draped-cloth".into(),
        bodies: vec![Body {
            label: "cloth".into(),
            model,
            state,
            method: Method::SemiImplicitEuler,
            params: MethodParams::default(),
        }],
        dt: 1e-4,
        duration: 1.0,
    }
}

/// The 2023 terrain with a 6 × 6 × 6 jelly (edge 3 m) turned 25° about (1, 0, 1) and sunk
/// half into the floor's hole, made by formula (no simulation): the bowl, the floor, the hole's
/// rim and a body both below and above the floor in one frame.
pub fn jelly_in_bowl() -> Scene {
    let spec = CubeSpec {
        counts: [6; 3],
        edge_length: DVec3::splat(3.0),
        mass: 1.0,
        coefficients: KindCoefficients::uniform(2000.0, 60.0),
        offset: DVec3::new(0.5, -1.6, -0.5),
        rotation: Some((DVec3::new(1.0, 0.0, 1.0), 25f64.to_radians())),
        ..CubeSpec::default()
    };
    let mut b = Builder::new();
    cube(&mut b, &spec);
    let (model, state) = b.build(DVec3::new(0.0, -9.8, 0.0), 0.0);
    Scene {
        name: "jelly-in-bowl".into(),
        bodies: vec![Body {
            label: "jelly".into(),
            model: model.with_colliders(
                Collider::course_2023_terrain(),
                ContactParams::course_2023(),
            ),
            state,
            method: Method::SemiImplicitEuler,
            params: MethodParams::default(),
        }],
        dt: 0.001,
        duration: 1.0,
    }
}

/// A free 4 × 4 × 4 spring cube (all three kinds) 1 m across, sheared and squashed by formula so
/// that springs of every kind show and their strains differ; no colliders, no gravity.
pub fn sheared_cube() -> Scene {
    let spec = CubeSpec {
        counts: [4; 3],
        edge_length: DVec3::splat(1.0),
        mass: 1.0,
        coefficients: KindCoefficients::uniform(500.0, 1.0),
        offset: DVec3::ZERO,
        rotation: None,
        ..CubeSpec::default()
    };
    let mut b = Builder::new();
    cube(&mut b, &spec);
    let (model, mut state) = b.build(DVec3::ZERO, 0.0);
    for p in &mut state.x {
        *p = DVec3::new(p.x + 0.35 * p.y, 0.8 * p.y, p.z * (1.0 + 0.15 * p.y));
    }
    Scene {
        name: "sheared-cube".into(),
        bodies: vec![Body {
            label: "cube".into(),
            model,
            state,
            method: Method::SemiImplicitEuler,
            params: MethodParams::default(),
        }],
        dt: 0.001,
        duration: 1.0,
    }
}
