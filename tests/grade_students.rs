//! A jelly homework written from the student README alone (no reference code) gets full marks:
//! the README's formulas, the `Physics` and `Matrix` API and the grader agree, including the
//! backward Euler step and the collision rules.

use springlab::grade::{
    Bowl, ContactCoefficients, DVec3, JellyHomework, Matrix, Options, Particle, Physics, Plane,
    Spring, SpringKind, SpringSetup, State, cube_index, flatten, grade_jelly, unflatten,
};

struct FromReadme;

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

impl JellyHomework for FromReadme {
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
        let d = xa - xb;
        -k * (d.length() - l0) * d / d.length()
    }

    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, kd: f64) -> DVec3 {
        let l = (xa - xb).normalize();
        -kd * (va - vb).dot(l) * l
    }

    fn internal_forces(&self, x: &[DVec3], v: &[DVec3], springs: &[Spring]) -> Vec<DVec3> {
        let mut f = vec![DVec3::ZERO; x.len()];
        for s in springs {
            let fa = self.spring_force(x[s.a], x[s.b], s.stiffness, s.rest_length)
                + self.damper_force(x[s.a], x[s.b], v[s.a], v[s.b], s.damping);
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
        let a = physics.accelerations(&s.x, &s.v);
        for ((x, v), a) in s.x.iter_mut().zip(s.v.iter_mut()).zip(a) {
            *x += dt * *v;
            *v += dt * a;
        }
    }

    fn implicit_euler(&self, s: &mut State, dt: f64, physics: &Physics) {
        let jx = physics.jacobian_x(&s.x, &s.v);
        let jv = physics.jacobian_v(&s.x, &s.v);
        let a = flatten(&physics.accelerations(&s.x, &s.v));
        let v = flatten(&s.v);
        let size = jx.size();
        // A = I - dt J_v - dt² J_x;  b = dt (a + dt J_x v)
        let mut big_a = Matrix::identity(size);
        for i in 0..size {
            for j in 0..size {
                big_a[(i, j)] -= dt * jv[(i, j)] + dt * dt * jx[(i, j)];
            }
        }
        let jxv = jx.mul_vec(&v);
        let b: Vec<f64> = (0..size).map(|i| dt * (a[i] + dt * jxv[i])).collect();
        let dv = unflatten(&big_a.solve(&b).expect("solvable"));
        for ((x, v), dv) in s.x.iter_mut().zip(s.v.iter_mut()).zip(dv) {
            *v += dv;
            *x += dt * *v;
        }
    }

    fn midpoint(&self, s: &mut State, dt: f64, physics: &Physics) {
        let a = physics.accelerations(&s.x, &s.v);
        let xm: Vec<DVec3> =
            s.x.iter()
                .zip(&s.v)
                .map(|(x, v)| *x + 0.5 * dt * *v)
                .collect();
        let vm: Vec<DVec3> =
            s.v.iter()
                .zip(&a)
                .map(|(v, a)| *v + 0.5 * dt * *a)
                .collect();
        let am = physics.accelerations(&xm, &vm);
        for i in 0..s.x.len() {
            s.x[i] += dt * vm[i];
            s.v[i] += dt * am[i];
        }
    }

    fn rk4(&self, s: &mut State, dt: f64, physics: &Physics) {
        let (x, v) = (s.x.clone(), s.v.clone());
        let n = x.len();
        let shifted = |kx: &[DVec3], kv: &[DVec3], h: f64| -> (Vec<DVec3>, Vec<DVec3>) {
            let xs: Vec<DVec3> = (0..n).map(|i| x[i] + h * kx[i]).collect();
            let vs: Vec<DVec3> = (0..n).map(|i| v[i] + h * kv[i]).collect();
            let a = physics.accelerations(&xs, &vs);
            (vs, a)
        };
        let (k1x, k1v) = (v.clone(), physics.accelerations(&x, &v));
        let (k2x, k2v) = shifted(&k1x, &k1v, 0.5 * dt);
        let (k3x, k3v) = shifted(&k2x, &k2v, 0.5 * dt);
        let (k4x, k4v) = shifted(&k3x, &k3v, dt);
        for i in 0..n {
            s.x[i] = x[i] + dt / 6.0 * (k1x[i] + 2.0 * k2x[i] + 2.0 * k3x[i] + k4x[i]);
            s.v[i] = v[i] + dt / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
        }
    }
}

#[test]
fn a_jelly_written_from_the_readme_gets_full_marks() {
    let report = grade_jelly(FromReadme, &Options::default());
    print!("{}", report.table());
    assert_eq!(report.score, report.max_score, "{}", report.table());
}
