// A correct rope homework, written from the student README against the student API alone.
// The grading tests copy it into real homework crates.

use springlab_homework::{DVec3, Mass, Physics, Rope, RopeHomework, Spring};

pub struct Student;

impl RopeHomework for Student {
    fn rope(
        &self,
        start: DVec3,
        end: DVec3,
        nodes: usize,
        node_mass: f64,
        stiffness: f64,
        pinned: &[usize],
    ) -> Rope {
        let masses: Vec<Mass> = (0..nodes)
            .map(|i| {
                let position = start + (end - start) * (i as f64 / (nodes - 1) as f64);
                Mass {
                    position,
                    velocity: DVec3::ZERO,
                    last_position: position,
                    mass: node_mass,
                    pinned: pinned.contains(&i),
                }
            })
            .collect();
        let springs = (0..nodes - 1)
            .map(|i| Spring {
                a: i,
                b: i + 1,
                rest_length: (masses[i + 1].position - masses[i].position).length(),
                stiffness,
                damping: 0.0,
            })
            .collect();
        Rope { masses, springs }
    }

    fn spring_force(&self, a: DVec3, b: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
        let d = b - a;
        let l = d.length();
        stiffness * d / l * (l - rest_length)
    }

    fn spring_forces(&self, rope: &Rope) -> Vec<DVec3> {
        let mut f = vec![DVec3::ZERO; rope.masses.len()];
        for s in &rope.springs {
            let fa = self.spring_force(
                rope.masses[s.a].position,
                rope.masses[s.b].position,
                s.stiffness,
                s.rest_length,
            );
            f[s.a] += fa;
            f[s.b] -= fa;
        }
        f
    }

    fn explicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {
        let a = physics.accelerations_of(rope);
        for (m, a) in rope.masses.iter_mut().zip(a) {
            if !m.pinned {
                m.position += dt * m.velocity;
                m.velocity += dt * a;
            }
        }
    }

    fn semi_implicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {
        let a = physics.accelerations_of(rope);
        for (m, a) in rope.masses.iter_mut().zip(a) {
            if !m.pinned {
                m.velocity += dt * a;
                m.position += dt * m.velocity;
            }
        }
    }

    fn verlet(&self, rope: &mut Rope, dt: f64, damping: f64, physics: &Physics) {
        let a = physics.accelerations_of(rope);
        for (m, a) in rope.masses.iter_mut().zip(a) {
            if !m.pinned {
                let x = m.position;
                m.position = x + (1.0 - damping) * (x - m.last_position) + a * dt * dt;
                m.last_position = x;
            }
        }
        for s in &rope.springs {
            let (pa, pb) = (rope.masses[s.a].pinned, rope.masses[s.b].pinned);
            let d = rope.masses[s.b].position - rope.masses[s.a].position;
            let l = d.length();
            let correction = d * ((l - s.rest_length) / l);
            match (pa, pb) {
                (true, true) => {}
                (true, false) => rope.masses[s.b].position -= correction,
                (false, true) => rope.masses[s.a].position += correction,
                (false, false) => {
                    rope.masses[s.a].position += 0.5 * correction;
                    rope.masses[s.b].position -= 0.5 * correction;
                }
            }
        }
    }
}
