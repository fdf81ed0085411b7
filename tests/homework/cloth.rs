// A correct cloth homework, written from the student README against the student API alone.

use springlab_homework::{
    Body, ClothHomework, DVec3, Matrix, Physics, Spring, SpringKind, SpringSetup, State,
    cloth_index, flatten, unflatten,
};

include!("integrators.rs");

pub struct Student;

impl ClothHomework for Student {
    fn springs(&self, n: usize) -> Vec<SpringSetup> {
        let n = n as i64;
        let mut out = Vec::new();
        let offsets: [(SpringKind, [(i64, i64); 2]); 3] = [
            (SpringKind::Struct, [(0, 1), (1, 0)]),
            (SpringKind::Shear, [(1, 1), (1, -1)]),
            (SpringKind::Bend, [(0, 2), (2, 0)]),
        ];
        for (kind, pair) in offsets {
            for r in 0..n {
                for c in 0..n {
                    for (dr, dc) in pair {
                        let (r2, c2) = (r + dr, c + dc);
                        if (0..n).contains(&r2) && (0..n).contains(&c2) {
                            out.push(SpringSetup {
                                a: cloth_index(n as usize, r as usize, c as usize),
                                b: cloth_index(n as usize, r2 as usize, c2 as usize),
                                kind,
                            });
                        }
                    }
                }
            }
        }
        out
    }

    fn spring_force(&self, xa: DVec3, xb: DVec3, k: f64, l0: f64) -> DVec3 {
        spring(xa, xb, k, l0)
    }

    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, kd: f64) -> DVec3 {
        damper(xa, xb, va, vb, kd)
    }

    fn spring_accelerations(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        w: &[f64],
        springs: &[Spring],
    ) -> Vec<DVec3> {
        let mut a = vec![DVec3::ZERO; x.len()];
        for s in springs {
            let fa = spring(x[s.a], x[s.b], s.stiffness, s.rest_length)
                + damper(x[s.a], x[s.b], v[s.a], v[s.b], s.damping);
            a[s.a] += w[s.a] * fa;
            a[s.b] -= w[s.b] * fa;
        }
        a
    }

    fn sphere_collision(&self, sphere: &mut Body, radius: f64, p: &mut Body, e: f64) {
        let d = p.x - sphere.x;
        let dist = d.length();
        if dist >= radius {
            return;
        }
        let n = d / dist;
        let (ws, wp) = (sphere.inverse_mass, p.inverse_mass);
        let v_rel = (p.v - sphere.v).dot(n);
        if v_rel < 0.0 {
            let j = -(1.0 + e) * v_rel / (ws + wp);
            sphere.v -= ws * j * n;
            p.v += wp * j * n;
        }
        let depth = radius - dist;
        sphere.x -= ws / (ws + wp) * depth * n;
        p.x += wp / (ws + wp) * depth * n;
    }

    fn explicit_euler(&self, s: &mut State, dt: f64, physics: &Physics) {
        explicit_euler(s, dt, physics);
    }

    fn implicit_euler(&self, s: &mut State, dt: f64, physics: &Physics) {
        implicit_euler(s, dt, physics);
    }

    fn midpoint(&self, s: &mut State, dt: f64, physics: &Physics) {
        midpoint(s, dt, physics);
    }

    fn rk4(&self, s: &mut State, dt: f64, physics: &Physics) {
        rk4(s, dt, physics);
    }
}
