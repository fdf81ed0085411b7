//! Lattice builders: the jelly cube (NYCU HW1 2021/2023, workload W1) and the cloth (NYCU HW1
//! 2022/2024, workload W2).
//!
//! # Theory
//!
//! A lattice body is a regular grid of particles joined by three kinds of springs (NYCU Computer
//! Animation HW1, "Mass-spring system", 2021–2024):
//!
//! - **struct** springs join direct neighbours along an axis and resist stretching;
//! - **shear** springs join diagonal neighbours and resist shearing;
//! - **bend** springs join particles two apart along an axis and resist bending (folding).
//!
//! Each spring is generated once, from its first end `a`, by walking a fixed list of lattice
//! offsets ("stencil") whose first non-zero component is positive; the second end `b` may have
//! the smaller index (cube offset (1,-1,0) gives `b = a + 1 - nx`). The order of the springs is canonical: kind by kind
//! (struct, then shear, then bend); within a kind particle by particle; within a particle offset
//! by offset in the order of the tables below. The peer benchmarks (`docs/workloads.md`, W1 and W2)
//! generate their springs in exactly this order, so the set-ups agree bit for bit.
//!
//! ```text
//! cube (dx, dy, dz)                                         count for nx × ny × nz particles
//! struct  (1,0,0) (0,1,0) (0,0,1)                           (nx-1)ny nz + nx(ny-1)nz + nx ny(nz-1)
//! shear   (1,1,0) (1,-1,0) (1,0,1) (1,0,-1) (0,1,1) (0,1,-1)    2(nx-1)(ny-1)nz + 2(nx-1)ny(nz-1)
//!         (1,1,1) (1,1,-1) (1,-1,1) (1,-1,-1)                      + 2 nx(ny-1)(nz-1) + 4(nx-1)(ny-1)(nz-1)
//! bend    (2,0,0) (0,2,0) (0,0,2)                           (nx-2)ny nz + nx(ny-2)nz + nx ny(nz-2)
//!
//! cloth (dr, dc)                                            count for n × n particles
//! struct  (0,1) (1,0)                                       2 n (n-1)
//! shear   (1,1) (1,-1)                                      2 (n-1)²
//! bend    (0,2) (2,0)                                       2 n (n-2)
//! ```
//! where `(dx, dy, dz)` are steps in lattice units along x, y, z and `(dr, dc)` are row and
//! column steps of the cloth. A 10 × 10 × 10 cube has 2 700 struct, 7 776 shear (4 860 face and
//! 2 916 body diagonals) and 2 400 bend springs, 12 876 in all; a 25 × 25 cloth has
//! 1 200 + 1 152 + 1 150, a 64 × 64 cloth 8 064 + 7 938 + 7 936 = 23 938.
//!
//! Every rest length is the initial distance `L0 = sqrt(d.x*d.x + d.y*d.y + d.z*d.z)` with
//! `d = x_b - x_a`, summed left to right ([`Builder::spring`]; glam's `length` computes exactly
//! this), so an undeformed lattice starts at rest with no elastic energy.
//!
//! References: NYCU Computer Animation HW1 2021 (cube), 2022 (cloth), 2023 (jelly), 2024 (cloth);
//! `docs/workloads.md` (peer benchmarks) W1 `jelly` and W2 `cloth`, section "Canonical set-up bytes".

use glam::{DQuat, DVec3};

use super::SceneError;
use super::builder::Builder;
use crate::physics::{Spring, SpringKind};

/// Stiffness (N/m) and damping (N·s/m) of each spring kind.
///
/// The course panels have one spring and one damper coefficient for all kinds; the fields are
/// separate so that a lesson can, say, soften only the bend springs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KindCoefficients {
    /// Struct springs: `(stiffness N/m, damping N·s/m)`.
    pub struct_: (f64, f64),
    /// Shear springs: `(stiffness N/m, damping N·s/m)`.
    pub shear: (f64, f64),
    /// Bend springs: `(stiffness N/m, damping N·s/m)`.
    pub bend: (f64, f64),
}

impl KindCoefficients {
    /// The same `stiffness` (N/m) and `damping` (N·s/m) for all three kinds.
    #[must_use]
    pub fn uniform(stiffness: f64, damping: f64) -> KindCoefficients {
        KindCoefficients {
            struct_: (stiffness, damping),
            shear: (stiffness, damping),
            bend: (stiffness, damping),
        }
    }

    /// `(stiffness N/m, damping N·s/m)` of `kind`.
    #[must_use]
    pub fn get(&self, kind: SpringKind) -> (f64, f64) {
        match kind {
            SpringKind::Struct => self.struct_,
            SpringKind::Shear => self.shear,
            SpringKind::Bend => self.bend,
        }
    }

    /// An error message when a coefficient is negative or not finite.
    fn check(&self) -> Result<(), SceneError> {
        for kind in SpringKind::ALL {
            let (k, kd) = self.get(kind);
            if !(k.is_finite() && k >= 0.0) {
                return Err(invalid(format!(
                    "{} stiffness must be a finite number >= 0 N/m, got {k}",
                    kind.name()
                )));
            }
            if !(kd.is_finite() && kd >= 0.0) {
                return Err(invalid(format!(
                    "{} damping must be a finite number >= 0 N·s/m, got {kd}",
                    kind.name()
                )));
            }
        }
        Ok(())
    }
}

impl Default for KindCoefficients {
    /// The course cube values: K = 2000 N/m, D = 60 N·s/m for every kind (NYCU HW1 2021/2023).
    fn default() -> KindCoefficients {
        KindCoefficients::uniform(2000.0, 60.0)
    }
}

/// Cube stencils `(dx, dy, dz)` in lattice units, per kind (see the module table).
const CUBE_STRUCT: [[i64; 3]; 3] = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
const CUBE_SHEAR: [[i64; 3]; 10] = [
    [1, 1, 0],
    [1, -1, 0],
    [1, 0, 1],
    [1, 0, -1],
    [0, 1, 1],
    [0, 1, -1],
    [1, 1, 1],
    [1, 1, -1],
    [1, -1, 1],
    [1, -1, -1],
];
const CUBE_BEND: [[i64; 3]; 3] = [[2, 0, 0], [0, 2, 0], [0, 0, 2]];

/// Cloth stencils `(dr, dc)` (row, column) per kind (see the module table).
const CLOTH_STRUCT: [[i64; 2]; 2] = [[0, 1], [1, 0]];
const CLOTH_SHEAR: [[i64; 2]; 2] = [[1, 1], [1, -1]];
const CLOTH_BEND: [[i64; 2]; 2] = [[0, 2], [2, 0]];

/// The cube stencil of `kind`: lattice offsets `(dx, dy, dz)` in generation order.
///
/// A spring joins particle `(ix, iy, iz)` and `(ix + dx, iy + dy, iz + dz)` when the latter is
/// inside the lattice. Struct 3, shear 10 (6 face and 4 body diagonals), bend 3 offsets.
#[must_use]
pub fn cube_offsets(kind: SpringKind) -> &'static [[i64; 3]] {
    match kind {
        SpringKind::Struct => &CUBE_STRUCT,
        SpringKind::Shear => &CUBE_SHEAR,
        SpringKind::Bend => &CUBE_BEND,
    }
}

/// The cloth stencil of `kind`: `(dr, dc)` row and column offsets in generation order.
#[must_use]
pub fn cloth_offsets(kind: SpringKind) -> &'static [[i64; 2]] {
    match kind {
        SpringKind::Struct => &CLOTH_STRUCT,
        SpringKind::Shear => &CLOTH_SHEAR,
        SpringKind::Bend => &CLOTH_BEND,
    }
}

/// A box-shaped lattice body: the course's cube (2021) and jelly (2023).
///
/// Particle `(ix, iy, iz)`, `0 <= ix < nx` etc., has index `p = ix + nx (iy + ny iz)` (x fastest)
/// and, before rotation, the position
///
/// ```text
/// x_p = offset + (ix · h_x, iy · h_y, iz · h_z)        h_a = edge_length_a / (n_a - 1)
/// ```
/// where
/// - `offset`: position of particle 0, the corner with the smallest coordinates (m)
/// - `h_a`: spacing along axis `a` (m), `n_a = counts[a]` particles along it
///
/// computed per component as `offset.x + f64(ix) * h_x`, so that `offset = (0, 1, 0)` and
/// `h = 0.1` reproduce W1's `(f64(ix) * 0.1, 1.0 + f64(iy) * 0.1, f64(iz) * 0.1)` bit for bit.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeSpec {
    /// Particles along x, y and z (`[nx, ny, nz]`), each at least 2.
    pub counts: [usize; 3],
    /// Edge length of the box along x, y and z (m), each > 0.
    pub edge_length: DVec3,
    /// Mass of each particle (kg), > 0.
    pub mass: f64,
    /// Stiffness and damping per spring kind.
    pub coefficients: KindCoefficients,
    /// Position of particle 0 before rotation: the corner with the smallest x, y and z (m).
    pub offset: DVec3,
    /// Optional rigid rotation `(axis, angle in rad)` about the box centre
    /// `offset + edge_length / 2`; the axis need not be normalised but must not be zero.
    pub rotation: Option<(DVec3, f64)>,
    /// The spring kinds to build; they are generated in the order struct, shear, bend whatever
    /// the order here, and a kind listed twice is built once.
    pub kinds: Vec<SpringKind>,
}

impl Default for CubeSpec {
    /// The course cube (NYCU HW1 2021): 10 × 10 × 10 particles of 1 kg, edge length 4 m,
    /// K = 2000 N/m and D = 60 N·s/m for all three kinds, corner at the start offset (0, 5, 0),
    /// no rotation.
    fn default() -> CubeSpec {
        CubeSpec {
            counts: [10, 10, 10],
            edge_length: DVec3::splat(4.0),
            mass: 1.0,
            coefficients: KindCoefficients::default(),
            offset: DVec3::new(0.0, 5.0, 0.0),
            rotation: None,
            kinds: SpringKind::ALL.to_vec(),
        }
    }
}

impl CubeSpec {
    /// Workload W1 `jelly` (`docs/workloads.md`): 10 × 10 × 10 particles of 1 kg at spacing 0.1 m
    /// (edge 0.9 m), bottom face at y = 1 m, k = 2000 N/m and k_d = 10 N·s/m for all kinds.
    #[must_use]
    pub fn w1_jelly() -> CubeSpec {
        CubeSpec {
            counts: [10, 10, 10],
            // 0.9 / 9 rounds to the same binary64 as 0.1, so the spacing is W1's h exactly.
            edge_length: DVec3::splat(0.9),
            mass: 1.0,
            coefficients: KindCoefficients::uniform(2000.0, 10.0),
            offset: DVec3::new(0.0, 1.0, 0.0),
            rotation: None,
            kinds: SpringKind::ALL.to_vec(),
        }
    }

    /// Number of particles `nx · ny · nz`.
    #[must_use]
    pub fn particle_count(&self) -> usize {
        self.counts.iter().product()
    }

    /// Spacing `h_a = edge_length_a / (n_a - 1)` along x, y and z (m).
    #[must_use]
    pub fn spacing(&self) -> DVec3 {
        DVec3::new(
            self.edge_length.x / (self.counts[0] as f64 - 1.0),
            self.edge_length.y / (self.counts[1] as f64 - 1.0),
            self.edge_length.z / (self.counts[2] as f64 - 1.0),
        )
    }

    /// The box centre `offset + edge_length / 2` (m), the pivot of [`CubeSpec::rotation`].
    #[must_use]
    pub fn centre(&self) -> DVec3 {
        self.offset + self.edge_length * 0.5
    }

    /// Checks everything [`cube`] relies on.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] with a message naming the field and the allowed range: a count
    /// below 2 or more particles than `u32` indices can address, an edge length that is not
    /// finite and positive, a mass that is not finite and positive, a negative or non-finite
    /// coefficient, a non-finite offset, or a zero or non-finite rotation axis or angle.
    pub fn validate(&self) -> Result<(), SceneError> {
        for (axis, &n) in ["x", "y", "z"].iter().zip(&self.counts) {
            if n < 2 {
                return Err(invalid(format!(
                    "the cube needs at least 2 particles along {axis}, got {n}"
                )));
            }
        }
        let total = self.counts[0]
            .checked_mul(self.counts[1])
            .and_then(|p| p.checked_mul(self.counts[2]));
        if total.is_none_or(|t| t > u32::MAX as usize) {
            return Err(invalid(format!(
                "the cube has too many particles ({} × {} × {}); at most {} are allowed",
                self.counts[0],
                self.counts[1],
                self.counts[2],
                u32::MAX
            )));
        }
        for (axis, e) in ["x", "y", "z"].iter().zip(self.edge_length.to_array()) {
            if !(e.is_finite() && e > 0.0) {
                return Err(invalid(format!(
                    "the cube's edge length along {axis} must be a finite number > 0 m, got {e}"
                )));
            }
        }
        check_mass(self.mass)?;
        self.coefficients.check()?;
        if !self.offset.is_finite() {
            return Err(invalid(format!(
                "the cube's offset must be finite, got {}",
                self.offset
            )));
        }
        if let Some((axis, angle)) = self.rotation {
            if !angle.is_finite() {
                return Err(invalid(format!(
                    "the rotation angle must be finite, got {angle} rad"
                )));
            }
            if axis.try_normalize().is_none() {
                return Err(invalid(format!(
                    "the rotation axis must be a finite, non-zero vector, got {axis}"
                )));
            }
        }
        Ok(())
    }
}

/// Where the course places body number `index` when several bodies share a scene
/// (NYCU HW1 2021/2023):
///
/// ```text
/// offset_index = base + (0, L, -2 L · index)
/// ```
/// where
/// - `base`: the scene's start offset (m), for example (0, 5, 0) in 2021
/// - `L`: the cube's edge length (m); consecutive bodies are one edge length apart along -z
/// - `index`: 0 for the first body
///
/// Use the result as [`CubeSpec::offset`].
#[must_use]
pub fn course_body_offset(index: usize, edge_length: f64, base: DVec3) -> DVec3 {
    base + DVec3::new(0.0, edge_length, -2.0 * edge_length * index as f64)
}

/// The course's reset rotation axis `(1, 0, 1) / √2` (NYCU HW1 2021/2023), for
/// [`CubeSpec::rotation`].
#[must_use]
pub fn course_rotation_axis() -> DVec3 {
    DVec3::new(1.0, 0.0, 1.0).normalize()
}

/// Adds a cube (jelly) lattice to `builder`; returns the index of its first particle.
///
/// Particles are added in the order `p = ix + nx (iy + ny iz)` at the positions of [`CubeSpec`];
/// with a rotation `(axis, θ)` every position then becomes `c + R(axis, θ) (x_p - c)` about the
/// centre `c = offset + edge_length / 2`. Springs follow, kind by kind (struct, shear, bend, those
/// in [`CubeSpec::kinds`]); within a kind
///
/// ```text
/// for p in particles { for (dx, dy, dz) in cube_offsets(kind) {
///     q = (ix + dx, iy + dy, iz + dz); if q inside: spring(p, q) } }
/// ```
/// with rest length = initial distance (see the module documentation). This is W1's
/// generation order, so [`CubeSpec::w1_jelly`] reproduces W1's set-up bytes.
///
/// # Panics
/// If [`CubeSpec::validate`] fails (scenes validate first and report the error).
pub fn cube(builder: &mut Builder, spec: &CubeSpec) -> u32 {
    if let Err(e) = spec.validate() {
        panic!("invalid cube: {e}");
    }
    let first = builder.len();
    assert!(
        first + spec.particle_count() <= u32::MAX as usize,
        "too many particles for u32 indices"
    );
    let [nx, ny, nz] = spec.counts;
    let h = spec.spacing();
    let rotation = spec
        .rotation
        .map(|(axis, angle)| DQuat::from_axis_angle(axis.normalize(), angle));
    let centre = spec.centre();
    for iz in 0..nz {
        for iy in 0..ny {
            for ix in 0..nx {
                // Component by component, offset + index · spacing (W1's arithmetic order).
                let mut x = DVec3::new(
                    spec.offset.x + ix as f64 * h.x,
                    spec.offset.y + iy as f64 * h.y,
                    spec.offset.z + iz as f64 * h.z,
                );
                if let Some(q) = rotation {
                    // Rigid rotation about the centre: c + R (x - c).
                    x = centre + q * (x - centre);
                }
                builder.particle(x, spec.mass);
            }
        }
    }
    let (nx, ny, nz) = (nx as i64, ny as i64, nz as i64);
    for kind in SpringKind::ALL {
        if !spec.kinds.contains(&kind) {
            continue;
        }
        let (stiffness, damping) = spec.coefficients.get(kind);
        for iz in 0..nz {
            for iy in 0..ny {
                for ix in 0..nx {
                    let p = ix + nx * (iy + ny * iz);
                    for &[dx, dy, dz] in cube_offsets(kind) {
                        let (jx, jy, jz) = (ix + dx, iy + dy, iz + dz);
                        if (0..nx).contains(&jx) && (0..ny).contains(&jy) && (0..nz).contains(&jz) {
                            let q = jx + nx * (jy + ny * jz);
                            builder.spring(
                                (first as i64 + p) as u32,
                                (first as i64 + q) as u32,
                                stiffness,
                                damping,
                                kind,
                            );
                        }
                    }
                }
            }
        }
    }
    first as u32
}

/// A square cloth of `n × n` particles in a horizontal (x-z) plane: the course cloth (NYCU HW1
/// 2022, 2024) and workload W2.
///
/// Particle `(r, c)` (row `r`, column `c`, `0 <= r, c < n`) has index `p = r n + c` and position
///
/// ```text
/// x_p = origin + (c · h_x, 0, r · h_z)          h_x = size[0] / (n - 1),  h_z = size[1] / (n - 1)
/// ```
/// where
/// - `origin`: position of particle 0, the corner with the smallest x and z; its y is the
///   cloth's height (m)
/// - `size`: extent of the cloth along x and along z (m)
///
/// computed per component as `(origin.x + f64(c) * h_x, origin.y, origin.z + f64(r) * h_z)`, so
/// that `origin = (0, 1, 0)`, `size = (1, 1)` reproduce W2's `(f64(c) * h, 1.0, f64(r) * h)`,
/// `h = 1.0 / (n - 1)`, bit for bit.
#[derive(Clone, Debug, PartialEq)]
pub struct ClothSpec {
    /// Particles per side, at least 2.
    pub n: usize,
    /// Position of particle 0 (m): minimum x and z corner; y is the height of the cloth.
    pub origin: DVec3,
    /// Extent along x and along z (m), each > 0.
    pub size: [f64; 2],
    /// Mass of each particle (kg), > 0.
    pub mass: f64,
    /// Stiffness and damping per spring kind.
    pub coefficients: KindCoefficients,
    /// Indices `p = r n + c` of the pinned particles (inverse mass 0); see [`corners`].
    pub pinned: Vec<usize>,
    /// The spring kinds to build; generated in the order struct, shear, bend whatever the order
    /// here, and a kind listed twice is built once.
    pub kinds: Vec<SpringKind>,
}

impl Default for ClothSpec {
    /// The 2024 course cloth ([`ClothSpec::course_2024`]).
    fn default() -> ClothSpec {
        ClothSpec::course_2024()
    }
}

impl ClothSpec {
    /// The course cloth of NYCU HW1 2022: 25 × 25 particles of 1 kg over x, z ∈ [-2, 2] m at
    /// y = 0, spring 25 000 N/m and damper 750 N·s/m for all kinds, the four corners pinned.
    #[must_use]
    pub fn course_2022() -> ClothSpec {
        ClothSpec {
            n: 25,
            origin: DVec3::new(-2.0, 0.0, -2.0),
            size: [4.0, 4.0],
            mass: 1.0,
            coefficients: KindCoefficients::uniform(25_000.0, 750.0),
            pinned: corners(25),
            kinds: SpringKind::ALL.to_vec(),
        }
    }

    /// The course cloth of NYCU HW1 2024: as [`ClothSpec::course_2022`] but at y = 1 m with
    /// spring 20 000 N/m.
    #[must_use]
    pub fn course_2024() -> ClothSpec {
        ClothSpec {
            origin: DVec3::new(-2.0, 1.0, -2.0),
            coefficients: KindCoefficients::uniform(20_000.0, 750.0),
            ..ClothSpec::course_2022()
        }
    }

    /// Workload W2 `cloth` (`docs/workloads.md`) with `n × n` particles (64 and 128 in the
    /// benchmark): the unit square at y = 1 m, total mass 1 kg (`m = 1 / n²` each),
    /// k = 5000 N/m, k_d = 0.02 N·s/m for all kinds, particles 0 and `n - 1` pinned.
    #[must_use]
    pub fn w2_cloth(n: usize) -> ClothSpec {
        ClothSpec {
            n,
            origin: DVec3::new(0.0, 1.0, 0.0),
            size: [1.0, 1.0],
            mass: 1.0 / (n as f64 * n as f64),
            coefficients: KindCoefficients::uniform(5000.0, 0.02),
            pinned: vec![0, n.saturating_sub(1)],
            kinds: SpringKind::ALL.to_vec(),
        }
    }

    /// Number of particles `n²`.
    #[must_use]
    pub fn particle_count(&self) -> usize {
        self.n * self.n
    }

    /// Spacing `(h_x, h_z) = size / (n - 1)` (m).
    #[must_use]
    pub fn spacing(&self) -> [f64; 2] {
        let cells = self.n as f64 - 1.0;
        [self.size[0] / cells, self.size[1] / cells]
    }

    /// Checks everything [`cloth`] relies on.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] with a message naming the field and the allowed range: `n < 2` or
    /// more particles than `u32` indices can address, a size that is not finite and positive, a
    /// mass that is not finite and positive, a negative or non-finite coefficient, a non-finite
    /// origin, or a pinned index `>= n²`.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.n < 2 {
            return Err(invalid(format!(
                "the cloth needs at least 2 particles per side, got {}",
                self.n
            )));
        }
        if self
            .n
            .checked_mul(self.n)
            .is_none_or(|t| t > u32::MAX as usize)
        {
            return Err(invalid(format!(
                "the cloth has too many particles ({0} × {0}); at most {1} are allowed",
                self.n,
                u32::MAX
            )));
        }
        for (axis, s) in ["x", "z"].iter().zip(self.size) {
            if !(s.is_finite() && s > 0.0) {
                return Err(invalid(format!(
                    "the cloth's size along {axis} must be a finite number > 0 m, got {s}"
                )));
            }
        }
        check_mass(self.mass)?;
        self.coefficients.check()?;
        if !self.origin.is_finite() {
            return Err(invalid(format!(
                "the cloth's origin must be finite, got {}",
                self.origin
            )));
        }
        let count = self.particle_count();
        if let Some(&p) = self.pinned.iter().find(|&&p| p >= count) {
            return Err(invalid(format!(
                "pinned particle {p} is out of range: the cloth has particles 0..={}",
                count - 1
            )));
        }
        Ok(())
    }
}

/// Adds a cloth lattice to `builder`; returns the index of its first particle.
///
/// Particles are added in the order `p = r n + c` at the positions of [`ClothSpec`], the
/// particles in [`ClothSpec::pinned`] pinned. Springs follow kind by kind (struct, shear, bend,
/// those in [`ClothSpec::kinds`]); within a kind
///
/// ```text
/// for p in particles { for (dr, dc) in cloth_offsets(kind) {
///     (r', c') = (r + dr, c + dc); if inside: spring(p, r' n + c') } }
/// ```
/// with rest length = initial distance. Counts for `n × n`: struct `2n(n-1)`, shear `2(n-1)²`,
/// bend `2n(n-2)`. This is W2's generation order, so [`ClothSpec::w2_cloth`] reproduces W2's
/// set-up bytes.
///
/// # Panics
/// If [`ClothSpec::validate`] fails (scenes validate first and report the error).
pub fn cloth(builder: &mut Builder, spec: &ClothSpec) -> u32 {
    if let Err(e) = spec.validate() {
        panic!("invalid cloth: {e}");
    }
    let first = builder.len();
    assert!(
        first + spec.particle_count() <= u32::MAX as usize,
        "too many particles for u32 indices"
    );
    let n = spec.n;
    let [hx, hz] = spec.spacing();
    for r in 0..n {
        for c in 0..n {
            // Component by component, origin + index · spacing (W2's arithmetic order).
            let x = DVec3::new(
                spec.origin.x + c as f64 * hx,
                spec.origin.y,
                spec.origin.z + r as f64 * hz,
            );
            builder.particle(x, spec.mass);
        }
    }
    for &p in &spec.pinned {
        builder.pinned[first + p] = true;
    }
    let n = n as i64;
    for kind in SpringKind::ALL {
        if !spec.kinds.contains(&kind) {
            continue;
        }
        let (stiffness, damping) = spec.coefficients.get(kind);
        for r in 0..n {
            for c in 0..n {
                for &[dr, dc] in cloth_offsets(kind) {
                    let (r2, c2) = (r + dr, c + dc);
                    if (0..n).contains(&r2) && (0..n).contains(&c2) {
                        builder.spring(
                            (first as i64 + r * n + c) as u32,
                            (first as i64 + r2 * n + c2) as u32,
                            stiffness,
                            damping,
                            kind,
                        );
                    }
                }
            }
        }
    }
    first as u32
}

/// The four corner indices of an `n × n` cloth, `[0, n - 1, n(n - 1), n² - 1]` (the course's
/// pinned set); fewer when they coincide (`n = 1` gives `[0]`, `n = 0` none).
#[must_use]
pub fn corners(n: usize) -> Vec<usize> {
    let mut c = Vec::with_capacity(4);
    if n == 0 {
        return c;
    }
    for p in [0, n - 1, n * (n - 1), n * n - 1] {
        if !c.contains(&p) {
            c.push(p);
        }
    }
    c
}

/// Number of springs of each kind, in the order of [`SpringKind::ALL`]: `[struct, shear, bend]`.
#[must_use]
pub fn count_kinds(springs: &[Spring]) -> [usize; 3] {
    let mut counts = [0; 3];
    for s in springs {
        let i = match s.kind {
            SpringKind::Struct => 0,
            SpringKind::Shear => 1,
            SpringKind::Bend => 2,
        };
        counts[i] += 1;
    }
    counts
}

/// The canonical set-up bytes of `docs/workloads.md` ("Canonical set-up bytes"): all positions as
/// little-endian f64 `x, y, z` per particle, then per spring `u32 a, u32 b, f64 rest_length`
/// (little-endian), in the order given.
///
/// Its SHA-256 identifies a set-up: equal hashes mean bit-identical positions, topology and
/// rest lengths (stiffness, damping, masses and pins are not included).
#[must_use]
pub fn setup_bytes(x: &[DVec3], springs: &[Spring]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(x.len() * 24 + springs.len() * 16);
    for p in x {
        for c in p.to_array() {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for s in springs {
        bytes.extend_from_slice(&s.a.to_le_bytes());
        bytes.extend_from_slice(&s.b.to_le_bytes());
        bytes.extend_from_slice(&s.rest_length.to_le_bytes());
    }
    bytes
}

fn invalid(message: String) -> SceneError {
    SceneError::Invalid(message)
}

fn check_mass(mass: f64) -> Result<(), SceneError> {
    if mass.is_finite() && mass > 0.0 {
        Ok(())
    } else {
        Err(invalid(format!(
            "the particle mass must be a finite number > 0 kg, got {mass}"
        )))
    }
}
