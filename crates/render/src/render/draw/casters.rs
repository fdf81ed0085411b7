//! What casts shadows: each body's surface, its outline seen from the light, its springs and
//! particles, and the spheres, gathered once per frame for [`super::super::shadow`].

use glam::DVec3;

use super::{BodyGeometry, Renderer};
use crate::physics::collide::Collider;
use crate::render::colour;
use crate::render::shadow::Casters;
use crate::render::surface::quad_edges;
use crate::scene::Scene;

impl Renderer {
    /// What casts shadows on the planes: each body's surface quads (a closed body's that face
    /// the light) or its shown springs and particles, with its spheres; then the static spheres.
    pub(super) fn casters(&self, scene: &Scene) -> Casters {
        let mut c = Casters::new();
        let light = colour::LIGHT;
        for (body, geom) in scene.bodies.iter().zip(&self.bodies) {
            let x = &body.state.x;
            let surface = geom.lattice.is_some() && geom.particles == x.len();
            if !geom.hull.is_empty() && geom.particles == x.len() {
                silhouette(geom, x, light, &mut c);
            } else if surface {
                for q in &geom.quads {
                    c.polygon(&q.map(|i| x[i as usize]));
                }
            } else if body.model.springs().len() <= 4000 {
                let half = 0.35 * geom.particle_radius;
                for spring in body.model.springs() {
                    let (a, b) = (spring.a as usize, spring.b as usize);
                    if self.style.springs.shows(spring.kind) && a < x.len() && b < x.len() {
                        c.strip(x[a], x[b], half);
                    }
                }
                if self.style.particles && x.len() <= 400 {
                    for &p in x {
                        c.ball(p, geom.particle_radius);
                    }
                }
            }
            if self.style.colliders {
                for sphere in &body.state.spheres {
                    c.ball(sphere.center, sphere.radius);
                }
            }
            c.end_group();
        }
        if self.style.colliders {
            for body in &scene.bodies {
                for col in &body.model.colliders {
                    if let Collider::Sphere { center, radius } = *col {
                        c.ball(center, radius);
                    }
                }
            }
            c.end_group();
        }
        c
    }
}

/// Unique edges of `quads` with the indices of the (one or two) quads they border.
pub(super) fn edges_with_quads(quads: &[[u32; 4]]) -> Vec<(u32, u32, [u32; 2])> {
    let edges = quad_edges(quads);
    let mut owners: Vec<[u32; 2]> = vec![[u32::MAX; 2]; edges.len()];
    for (qi, q) in quads.iter().enumerate() {
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            let key = (a.min(b), a.max(b));
            if let Ok(e) = edges.binary_search(&key) {
                let o = &mut owners[e];
                if o[0] == u32::MAX {
                    o[0] = qi as u32;
                } else {
                    o[1] = qi as u32;
                }
            }
        }
    }
    edges
        .into_iter()
        .zip(owners)
        .map(|((a, b), o)| (a, b, [o[0], if o[1] == u32::MAX { o[0] } else { o[1] }]))
        .collect()
}

/// The outlines of a closed body seen from the light, as polygons of `casters`: the hull's
/// edges between a quad that faces the light and one that does not, chained into loops, each
/// run the way its lit quad runs (so that every loop turns the same way seen from the light).
fn silhouette(geom: &BodyGeometry, x: &[DVec3], light: DVec3, casters: &mut Casters) {
    let lit: Vec<bool> = geom
        .hull
        .iter()
        .map(|q| {
            let [a, b, c, d] = q.map(|i| x[i as usize]);
            (c - a).cross(d - b).dot(light) > 0.0
        })
        .collect();
    // Directed silhouette edges, sorted by their start for the walk.
    let mut edges: Vec<(u32, u32)> = geom
        .hull_edges
        .iter()
        .filter(|(_, _, q, _)| lit[q[0] as usize] != lit[q[1] as usize])
        .map(|&(a, b, q, forward)| {
            // The lit quad's direction: the first quad's, or the reverse for the second.
            if lit[q[0] as usize] == forward {
                (a, b)
            } else {
                (b, a)
            }
        })
        .collect();
    edges.sort_unstable();
    let mut used = vec![false; edges.len()];
    let mut ring = Vec::new();
    for first in 0..edges.len() {
        if used[first] {
            continue;
        }
        ring.clear();
        let mut e = first;
        loop {
            used[e] = true;
            ring.push(x[edges[e].0 as usize]);
            let next = edges[e].1;
            let start = edges.partition_point(|&(a, _)| a < next);
            match (start..edges.len())
                .take_while(|&k| edges[k].0 == next)
                .find(|&k| !used[k])
            {
                Some(k) => e = k,
                None => break,
            }
        }
        if ring.len() >= 3 {
            casters.polygon(&ring);
        }
    }
}
