// A correct jelly homework, written from the student README against the student API alone.

use springlab_homework::{
    Bowl, ContactCoefficients, DVec3, JellyHomework, Matrix, Particle, Physics, Plane, Spring,
    SpringKind, SpringSetup, State, cube_index, flatten, unflatten,
};

include!("integrators.rs");

pub struct Student;

const STRUCT: [[i64; 3]; 3] = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
const SHEAR: [[i64; 3]; 10] = [
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
const BEND: [[i64; 3]; 3] = [[2, 0, 0], [0, 2, 0], [0, 0, 2]];

/// The contact rules of the README for a surface with distance `phi` and normal `n` at `p.x`.
fn contact(p: &mut Particle, phi: f64, n: DVec3, c: &ContactCoefficients) {
    if phi >= c.epsilon {
        return;
    }
    let vn = p.v.dot(n);
    let v_t = p.v - vn * n;
    let push = n.dot(p.force);
    if vn <= 0.0 && push < 0.0 {
        p.force += -push * n - c.friction * (-push) * v_t / v_t.length();
    }
    if vn < 0.0 {
        p.v = -c.restitution * vn * n + v_t;
    }
    if phi < 0.0 {
        p.x -= phi * n;
    }
}

impl JellyHomework for Student {
    fn springs(&self, counts: [usize; 3]) -> Vec<SpringSetup> {
        let mut out = Vec::new();
        let n = counts.map(|c| c as i64);
        for (kind, offsets) in [
            (SpringKind::Struct, &STRUCT[..]),
            (SpringKind::Shear, &SHEAR[..]),
            (SpringKind::Bend, &BEND[..]),
        ] {
            for iz in 0..n[2] {
                for iy in 0..n[1] {
                    for ix in 0..n[0] {
                        for o in offsets {
                            let (jx, jy, jz) = (ix + o[0], iy + o[1], iz + o[2]);
                            if (0..n[0]).contains(&jx)
                                && (0..n[1]).contains(&jy)
                                && (0..n[2]).contains(&jz)
                            {
                                out.push(SpringSetup {
                                    a: cube_index(counts, ix as usize, iy as usize, iz as usize),
                                    b: cube_index(counts, jx as usize, jy as usize, jz as usize),
                                    kind,
                                });
                            }
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

    fn internal_forces(&self, x: &[DVec3], v: &[DVec3], springs: &[Spring]) -> Vec<DVec3> {
        let mut f = vec![DVec3::ZERO; x.len()];
        for s in springs {
            let fa = spring(x[s.a], x[s.b], s.stiffness, s.rest_length)
                + damper(x[s.a], x[s.b], v[s.a], v[s.b], s.damping);
            f[s.a] += fa;
            f[s.b] -= fa;
        }
        f
    }

    fn plane_collision(&self, plane: &Plane, p: &mut Particle, c: &ContactCoefficients) {
        let phi = (p.x - plane.point).dot(plane.normal);
        contact(p, phi, plane.normal, c);
    }

    fn bowl_collision(&self, bowl: &Bowl, p: &mut Particle, c: &ContactCoefficients) {
        if p.x.y > bowl.rim_height {
            return;
        }
        let phi = bowl.radius - (p.x - bowl.center).length();
        let n = (bowl.center - p.x).normalize();
        contact(p, phi, n, c);
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
