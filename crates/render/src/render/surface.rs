//! Surfaces of lattice bodies: a cloth is drawn as its sheet, a jelly cube as its six faces.
//!
//! # Theory
//!
//! A body needs no hint to be drawn as a surface: its struct springs say what it is. The
//! lattice builders ([`crate::scene::lattice`]) number particles row by row, so
//!
//! ```text
//! grid  rows × cols:      p = r · cols + c         struct springs join p, p + 1 and p, p + cols
//! block nx × ny × nz:     p = ix + nx (iy + ny iz)  struct springs join p, p + 1 / p + nx / p + nx ny
//! ```
//! A body is a grid (cloth) when its struct springs have exactly the two index offsets `1` and
//! `cols`, the particle count is `rows · cols` with `rows, cols ≥ 2`, and the struct springs are
//! exactly the `rows (cols - 1) + cols (rows - 1)` grid edges; a block likewise with the offsets
//! `1`, `nx`, `nx ny`. Anything else (a rope, a hand-written scene, a lattice without struct
//! springs) is drawn as springs and particles.
//!
//! The surface is a list of quads `[p0, p1, p2, p3]` in counter-clockwise order seen from the
//! side their normal points to, `N = (x_2 - x_0) × (x_3 - x_1)`; each quad is drawn as the two
//! triangles `(p0, p1, p2)` and `(p0, p2, p3)`. A block's quads are its boundary faces with
//! normals pointing outwards, so faces turned away from the camera can be skipped; a grid's
//! normal is `(x_{r+1,c} - x_{r,c}) × (x_{r,c+1} - x_{r,c})`, which is `+y` for the course cloth
//! (rows along +z, columns along +x).

use std::collections::BTreeSet;

use crate::physics::{Model, SpringKind};

/// What kind of lattice a body is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lattice {
    /// A cloth: `rows × cols` particles, `p = r · cols + c`.
    Grid {
        /// Number of rows (≥ 2).
        rows: usize,
        /// Number of columns (≥ 2).
        cols: usize,
    },
    /// A jelly cube: `nx × ny × nz` particles, `p = ix + nx (iy + ny iz)`.
    Block {
        /// Particles along x (≥ 2).
        nx: usize,
        /// Particles along y (≥ 2).
        ny: usize,
        /// Particles along z (≥ 2).
        nz: usize,
    },
}

impl Lattice {
    /// Recognises a grid or block from the struct springs of `model` (module docs), or `None`.
    #[must_use]
    pub fn detect(model: &Model) -> Option<Lattice> {
        let n = model.particle_count();
        let mut edges: BTreeSet<(usize, usize)> = BTreeSet::new();
        let mut offsets: BTreeSet<usize> = BTreeSet::new();
        for s in model
            .springs()
            .iter()
            .filter(|s| s.kind == SpringKind::Struct)
        {
            let (a, b) = (s.a.min(s.b) as usize, s.a.max(s.b) as usize);
            if a == b || !edges.insert((a, b)) {
                return None;
            }
            offsets.insert(b - a);
            if offsets.len() > 3 {
                return None;
            }
        }
        let offsets: Vec<usize> = offsets.into_iter().collect();
        let lattice = match offsets.as_slice() {
            [1, cols] if n.is_multiple_of(*cols) && n / cols >= 2 => Lattice::Grid {
                rows: n / cols,
                cols: *cols,
            },
            [1, nx, nxy]
                if nxy.is_multiple_of(*nx)
                    && n.is_multiple_of(*nxy)
                    && n / nxy >= 2
                    && nxy / nx >= 2 =>
            {
                Lattice::Block {
                    nx: *nx,
                    ny: nxy / nx,
                    nz: n / nxy,
                }
            }
            _ => return None,
        };
        (lattice.struct_edges() == edges).then_some(lattice)
    }

    /// The struct-spring edges `(a, b)`, `a < b`, of a complete lattice of this shape.
    fn struct_edges(&self) -> BTreeSet<(usize, usize)> {
        let mut e = BTreeSet::new();
        match *self {
            Lattice::Grid { rows, cols } => {
                for r in 0..rows {
                    for c in 0..cols {
                        let p = r * cols + c;
                        if c + 1 < cols {
                            e.insert((p, p + 1));
                        }
                        if r + 1 < rows {
                            e.insert((p, p + cols));
                        }
                    }
                }
            }
            Lattice::Block { nx, ny, nz } => {
                for iz in 0..nz {
                    for iy in 0..ny {
                        for ix in 0..nx {
                            let p = ix + nx * (iy + ny * iz);
                            if ix + 1 < nx {
                                e.insert((p, p + 1));
                            }
                            if iy + 1 < ny {
                                e.insert((p, p + nx));
                            }
                            if iz + 1 < nz {
                                e.insert((p, p + nx * ny));
                            }
                        }
                    }
                }
            }
        }
        e
    }

    /// The surface quads (module docs): every cell of a grid, or the boundary faces of a block
    /// with outward normals.
    #[must_use]
    pub fn quads(&self) -> Vec<[u32; 4]> {
        let mut q = Vec::new();
        match *self {
            Lattice::Grid { rows, cols } => {
                for r in 0..rows - 1 {
                    for c in 0..cols - 1 {
                        let p = (r * cols + c) as u32;
                        let (right, down) = (1, cols as u32);
                        // Counter-clockwise seen from (x_{r+1,c} - x_{r,c}) × (x_{r,c+1} - x_{r,c}).
                        q.push([p, p + down, p + down + right, p + right]);
                    }
                }
            }
            Lattice::Block { nx, ny, nz } => {
                let idx = |ix: usize, iy: usize, iz: usize| (ix + nx * (iy + ny * iz)) as u32;
                // x = const faces: quad over (y, z).
                for (ix, outward) in [(0, false), (nx - 1, true)] {
                    for iz in 0..nz - 1 {
                        for iy in 0..ny - 1 {
                            let quad = [
                                idx(ix, iy, iz),
                                idx(ix, iy + 1, iz),
                                idx(ix, iy + 1, iz + 1),
                                idx(ix, iy, iz + 1),
                            ];
                            q.push(oriented(quad, outward));
                        }
                    }
                }
                // y = const faces: quad over (z, x).
                for (iy, outward) in [(0, false), (ny - 1, true)] {
                    for ix in 0..nx - 1 {
                        for iz in 0..nz - 1 {
                            let quad = [
                                idx(ix, iy, iz),
                                idx(ix, iy, iz + 1),
                                idx(ix + 1, iy, iz + 1),
                                idx(ix + 1, iy, iz),
                            ];
                            q.push(oriented(quad, outward));
                        }
                    }
                }
                // z = const faces: quad over (x, y).
                for (iz, outward) in [(0, false), (nz - 1, true)] {
                    for iy in 0..ny - 1 {
                        for ix in 0..nx - 1 {
                            let quad = [
                                idx(ix, iy, iz),
                                idx(ix + 1, iy, iz),
                                idx(ix + 1, iy + 1, iz),
                                idx(ix, iy + 1, iz),
                            ];
                            q.push(oriented(quad, outward));
                        }
                    }
                }
            }
        }
        q
    }

    /// True for a closed surface (a block): its back faces are hidden.
    #[must_use]
    pub fn is_closed(&self) -> bool {
        matches!(self, Lattice::Block { .. })
    }
}

/// `quad` as given (normal along +axis) when `outward`, reversed otherwise.
fn oriented(quad: [u32; 4], outward: bool) -> [u32; 4] {
    if outward {
        quad
    } else {
        [quad[0], quad[3], quad[2], quad[1]]
    }
}

/// The unique edges `(a, b)`, `a < b`, of `quads`, in a fixed order.
#[must_use]
pub fn quad_edges(quads: &[[u32; 4]]) -> Vec<(u32, u32)> {
    let mut set = BTreeSet::new();
    for q in quads {
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            set.insert((a.min(b), a.max(b)));
        }
    }
    set.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::scene::builder::{Builder, RopeSpec, rope};
    use crate::scene::lattice::{ClothSpec, CubeSpec, cloth, cube};

    #[test]
    fn cloth_is_a_grid_with_upward_quads() {
        let mut b = Builder::new();
        cloth(
            &mut b,
            &ClothSpec {
                n: 5,
                pinned: vec![],
                ..ClothSpec::default()
            },
        );
        let (model, state) = b.build(DVec3::ZERO, 0.0);
        let l = Lattice::detect(&model).expect("a grid");
        assert_eq!(l, Lattice::Grid { rows: 5, cols: 5 });
        let quads = l.quads();
        assert_eq!(quads.len(), 16);
        for q in quads {
            let x = |i: usize| state.x[q[i] as usize];
            let n = (x(2) - x(0)).cross(x(3) - x(1));
            assert!(n.y > 0.0);
        }
    }

    #[test]
    fn cube_is_a_block_with_outward_faces() {
        let mut b = Builder::new();
        cube(
            &mut b,
            &CubeSpec {
                counts: [3, 4, 5],
                ..CubeSpec::default()
            },
        );
        let (model, state) = b.build(DVec3::ZERO, 0.0);
        let l = Lattice::detect(&model).expect("a block");
        assert_eq!(
            l,
            Lattice::Block {
                nx: 3,
                ny: 4,
                nz: 5
            }
        );
        let quads = l.quads();
        assert_eq!(quads.len(), 2 * (2 * 3 + 2 * 4 + 3 * 4));
        let centre = state.centroid();
        for q in quads {
            let x = |i: usize| state.x[q[i] as usize];
            let n = (x(2) - x(0)).cross(x(3) - x(1));
            let mid = (x(0) + x(1) + x(2) + x(3)) / 4.0;
            assert!(n.dot(mid - centre) > 0.0, "outward");
        }
    }

    #[test]
    fn rope_and_incomplete_lattices_are_not_surfaces() {
        let mut b = Builder::new();
        rope(
            &mut b,
            &RopeSpec {
                start: DVec3::ZERO,
                end: DVec3::X,
                nodes: 6,
                node_mass: 1.0,
                stiffness: 1.0,
                damping: 0.0,
                pinned: vec![],
            },
        );
        let (model, _) = b.build(DVec3::ZERO, 0.0);
        assert_eq!(Lattice::detect(&model), None);

        let mut b = Builder::new();
        cloth(
            &mut b,
            &ClothSpec {
                n: 4,
                pinned: vec![],
                ..ClothSpec::default()
            },
        );
        b.springs.remove(3);
        let (model, _) = b.build(DVec3::ZERO, 0.0);
        assert_eq!(Lattice::detect(&model), None);
    }
}
