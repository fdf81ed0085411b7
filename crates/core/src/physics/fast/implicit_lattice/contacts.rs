//! Which particles a step carries inside a sphere: the lattice's test eight particles at a time,
//! so that the contact search looks only at those.

use super::*;

/// The particles that `x + dt (v + Δv)` puts inside one of the spheres `ends` (centre in m,
/// radius in m), in order, into `out`: eight particles at a time, with the same arithmetic as
/// the contact search's test (`|x̃ - c|² < r²`, in `implicit_euler::nearest_contact`), so that
/// the search needs to look only at these. `x` (m), `v` and `dv` (m/s) have one entry per
/// particle.
pub(crate) fn inside_spheres(
    kernel: Kernel,
    x: &[DVec3],
    v: &[DVec3],
    dv: &[DVec3],
    dt: f64,
    ends: &[(DVec3, f64)],
    out: &mut Vec<usize>,
) {
    assert!(v.len() == x.len() && dv.len() == x.len());
    out.clear();
    inside_on(kernel, x, v, dv, dt, ends, out);
}

#[inline(always)]
fn inside_body<V: Lanes>(
    x: &[DVec3],
    v: &[DVec3],
    dv: &[DVec3],
    dt: f64,
    ends: &[(DVec3, f64)],
    out: &mut Vec<usize>,
) {
    let dt_v = V::splat(dt);
    for q in (0..x.len()).step_by(LANES) {
        let count = (x.len() - q).min(LANES);
        let (xq, vq, dq) = (
            load_chunk::<V>(&x[q..], count),
            load_chunk::<V>(&v[q..], count),
            load_chunk::<V>(&dv[q..], count),
        );
        let end = [
            xq[0].add(dt_v.mul(vq[0].add(dq[0]))),
            xq[1].add(dt_v.mul(vq[1].add(dq[1]))),
            xq[2].add(dt_v.mul(vq[2].add(dq[2]))),
        ];
        let mut inside = 0u8;
        for &(center, radius) in ends {
            let d = [
                end[0].sub(V::splat(center.x)),
                end[1].sub(V::splat(center.y)),
                end[2].sub(V::splat(center.z)),
            ];
            let distance2 = d[0].mul(d[0]).add(d[1].mul(d[1])).add(d[2].mul(d[2]));
            inside |= distance2.less_than(V::splat(radius * radius));
        }
        let mut bits = inside & first_lanes(count);
        while bits != 0 {
            out.push(q + bits.trailing_zeros() as usize);
            bits &= bits - 1;
        }
    }
}

on_lanes!(
    inside_on(kernel),
    inside_body,
    (
        x: &[DVec3],
        v: &[DVec3],
        dv: &[DVec3],
        dt: f64,
        ends: &[(DVec3, f64)],
        out: &mut Vec<usize>
    ) -> ()
);
