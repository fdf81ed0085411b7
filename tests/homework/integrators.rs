// The four integrators of the NYCU assignments, written from the student README; shared by the
// jelly and cloth solutions below (`include!`d into each).

fn explicit_euler(s: &mut State, dt: f64, physics: &Physics) {
    let a = physics.accelerations(&s.x, &s.v);
    for ((x, v), a) in s.x.iter_mut().zip(s.v.iter_mut()).zip(a) {
        *x += dt * *v;
        *v += dt * a;
    }
}

fn implicit_euler(s: &mut State, dt: f64, physics: &Physics) {
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

fn midpoint(s: &mut State, dt: f64, physics: &Physics) {
    let a = physics.accelerations(&s.x, &s.v);
    let xm: Vec<DVec3> = s.x.iter().zip(&s.v).map(|(x, v)| *x + 0.5 * dt * *v).collect();
    let vm: Vec<DVec3> = s.v.iter().zip(&a).map(|(v, a)| *v + 0.5 * dt * *a).collect();
    let am = physics.accelerations(&xm, &vm);
    for i in 0..s.x.len() {
        s.x[i] += dt * vm[i];
        s.v[i] += dt * am[i];
    }
}

fn rk4(s: &mut State, dt: f64, physics: &Physics) {
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

fn spring(xa: DVec3, xb: DVec3, k: f64, l0: f64) -> DVec3 {
    let d = xa - xb;
    -k * (d.length() - l0) * d / d.length()
}

fn damper(xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, kd: f64) -> DVec3 {
    let l = (xa - xb).normalize();
    -kd * (va - vb).dot(l) * l
}
