//! Many semi-implicit Euler steps of a small lattice in one call, with the particles kept in
//! the structure-of-arrays form between the steps.
//!
//! A rope of 64 particles has 63 springs: one pass of the streaming loop ([`super::passes`])
//! is a few hundred nanoseconds, and much of it is fixed cost: the copy of the positions and
//! velocities into the structure of arrays and back, the rings, the tile loop. Here the copy is
//! made once for all the steps of a call, and the springs' forces go to one flat array per
//! offset group (the whole lattice is one tile):
//!
//! ```text
//! copy x, v in (structure of arrays, zero past the last particle)
//! each step:  pass 1, each chunk p, each group δ with p < starts:
//!                 f_δ[p..p+8] → F_δ[δ + p..];   plus[p] = (0 + f_δ₁) + f_δ₂ + …
//!             pass 2, each chunk q:  minus = 0 + F_δ₁[q..q+8] + F_δ₂[q..q+8] + …
//!                 F = plus - minus;  f = (m g - c v) + F;  a = f · (1/m)
//!                 v' = v + dt a;  x' = x + dt v'          (in place: pass 1 is done)
//! copy x, v out
//! ```
//! where `F_δ` holds `δ` zeros before the first spring (a particle `q < δ` ends no spring of
//! that offset). These are the operations of the streaming loop with
//! [`Update::SemiImplicitEuler`], with the same kernels, in the same order, so the numbers are
//! the same bit for bit as that many single steps (tested). Only for small lattices without
//! colliders, dissipated-power accounting or per-step projections (see
//! [`Stencil::semi_implicit_euler_steps`]).

#[cfg(target_arch = "x86_64")]
use super::kernels::springs_avx512;
use super::kernels::springs_exact;
use super::passes::{Forces, Window, load_padded, semi_implicit_euler, weight_drag_springs};
#[allow(clippy::wildcard_imports)]
use super::*;

/// Up to this many particles a lattice is "small": its state stays in the first-level cache,
/// and one thread does the whole pass (see `MIN_SLOTS_PER_PART`).
pub(super) const SMALL_PARTICLES: usize = 256;

/// The arrays of a call (reused, so calls do not allocate).
#[derive(Default)]
pub(super) struct SmallScratch {
    x: [Vec<f64>; 3],
    v: [Vec<f64>; 3],
    /// `plus[c]`: the forces of the springs starting at each particle (N).
    plus: [Vec<f64>; 3],
    /// Per group: its springs' forces, after `δ` zeros (N), three components.
    forces: Vec<[Vec<f64>; 3]>,
}

thread_local! {
    static SMALL: RefCell<SmallScratch> = RefCell::new(SmallScratch::default());
}

impl Stencil {
    /// `steps` semi-implicit Euler steps of `dt` seconds (see [`Update::SemiImplicitEuler`]) of
    /// the positions `x` (m) and velocities `v` (m/s) under `dynamics`, in one call: the same
    /// numbers bit for bit as `steps` calls of [`Stencil::write`] with
    /// [`Output::Step`] (`after` none) each followed by swapping in the outputs.
    ///
    /// Returns false, and changes nothing, unless the lattice is small (at most 256 particles,
    /// `SMALL_PARTICLES`) and `dynamics` has no colliders.
    ///
    /// # Panics
    /// If a slice is shorter than the stencil's particle count.
    pub fn semi_implicit_euler_steps(
        &self,
        x: &mut [DVec3],
        v: &mut [DVec3],
        dynamics: &Dynamics,
        dt: f64,
        steps: u64,
    ) -> bool {
        let n = self.particles;
        if n > SMALL_PARTICLES || !dynamics.colliders.is_empty() {
            return false;
        }
        let (x, v) = (&mut x[..n], &mut v[..n]);
        assert!(
            dynamics.mass.len() >= n && dynamics.inv_mass.len() >= n,
            "masses too short"
        );
        SMALL.with(|s| {
            let s = &mut *s.borrow_mut();
            s.load(self, x, v);
            match self.kernel {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `with_kernel` and `Kernel::best` only choose `Avx512` on a CPU that
                // supports AVX-512F.
                Kernel::Avx512 => unsafe { steps_avx512(self, s, dynamics, dt, steps) },
                #[cfg(target_arch = "x86_64")]
                // SAFETY: as above, AVX2.
                Kernel::Avx2 => unsafe { steps_avx2(self, s, dynamics, dt, steps) },
                _ => small_body::<Plain>(
                    self,
                    s,
                    dynamics,
                    dt,
                    steps,
                    #[inline(always)]
                    #[allow(clippy::redundant_closure)]
                    |g, first, w, i, p| springs_exact::<Plain>(g, first, w, i, p),
                ),
            }
            s.store(x, v);
        });
        true
    }
}

impl SmallScratch {
    /// Sizes the arrays for `st` and copies `x`, `v` in (zero past the last particle).
    fn load(&mut self, st: &Stencil, x: &[DVec3], v: &[DVec3]) {
        let n = st.particles;
        // As the streaming loop's window: the springs' second ends up to `n + reach`.
        let len = n.next_multiple_of(LANES) + st.reach;
        for c in self.x.iter_mut().chain(&mut self.v) {
            c.clear();
            c.resize(len, 0.0);
        }
        for c in &mut self.plus {
            c.clear();
            c.resize(n.next_multiple_of(LANES), 0.0);
        }
        self.forces.resize_with(st.groups.len(), Default::default);
        for (g, f) in st.groups.iter().zip(&mut self.forces) {
            for c in f {
                c.clear();
                c.resize(g.delta + n.next_multiple_of(LANES), 0.0);
            }
        }
        for (i, (p, u)) in x.iter().zip(v).enumerate() {
            (self.x[0][i], self.x[1][i], self.x[2][i]) = (p.x, p.y, p.z);
            (self.v[0][i], self.v[1][i], self.v[2][i]) = (u.x, u.y, u.z);
        }
    }

    /// Copies the positions and velocities out.
    fn store(&self, x: &mut [DVec3], v: &mut [DVec3]) {
        for (i, (p, u)) in x.iter_mut().zip(v).enumerate() {
            *p = DVec3::new(self.x[0][i], self.x[1][i], self.x[2][i]);
            *u = DVec3::new(self.v[0][i], self.v[1][i], self.v[2][i]);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn steps_avx512(st: &Stencil, s: &mut SmallScratch, d: &Dynamics, dt: f64, steps: u64) {
    small_body::<Avx512>(
        st,
        s,
        d,
        dt,
        steps,
        #[inline(always)]
        |g, first, w, i, p| {
            // SAFETY: this function only runs on a CPU with AVX-512F, and `small_body` calls
            // with chunks inside the window and the group's arrays.
            unsafe { springs_avx512(g, first, w, i, p) }
        },
    );
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn steps_avx2(st: &Stencil, s: &mut SmallScratch, d: &Dynamics, dt: f64, steps: u64) {
    small_body::<Avx2>(
        st,
        s,
        d,
        dt,
        steps,
        #[inline(always)]
        #[allow(clippy::redundant_closure)]
        |g, first, w, i, p| springs_exact::<Avx2>(g, first, w, i, p),
    );
}

/// The steps of the module docs, with `springs` computing each chunk of springs (as in
/// `range_body`, whose `i` is `p` here: the window starts at particle 0).
#[inline(always)]
fn small_body<V: Lanes>(
    st: &Stencil,
    s: &mut SmallScratch,
    d: &Dynamics,
    dt: f64,
    steps: u64,
    springs: impl Fn(&Group, &[V; 6], &Window, usize, usize) -> (Forces<V>, V),
) {
    let n = st.particles;
    let SmallScratch {
        x: xs,
        v: vs,
        plus,
        forces,
    } = s;
    let dt_lanes = V::splat(dt);
    for _ in 0..steps {
        // Pass 1: every spring once, into its group's array, and the sums `plus`.
        {
            let w = Window {
                x: [&xs[0], &xs[1], &xs[2]],
                v: [&vs[0], &vs[1], &vs[2]],
            };
            for p in (0..n).step_by(LANES) {
                let first = w.first_ends::<V>(p);
                let mut sum = [V::zero(); 3];
                for (g, out) in st.groups.iter().zip(forces.iter_mut()) {
                    if p >= g.starts {
                        // The groups a chunk has are a prefix of the list.
                        break;
                    }
                    let (f, _) = springs(g, &first, &w, p, p);
                    for ((part, total), values) in f.into_iter().zip(&mut sum).zip(out) {
                        part.store(chunk_mut(values, g.delta + p));
                        *total = total.add(part);
                    }
                }
                for (total, values) in sum.into_iter().zip(plus.iter_mut()) {
                    total.store(chunk_mut(values, p));
                }
            }
        }
        // Pass 2: minus the springs that end here, then the step, in place.
        for q in (0..n).step_by(LANES) {
            let count = (n - q).min(LANES);
            let mut minus = [V::zero(); 3];
            for f in forces.iter() {
                for (total, values) in minus.iter_mut().zip(f) {
                    *total = total.add(V::load(lanes(values, q)));
                }
            }
            let sum = [
                V::load(lanes(&plus[0], q)).sub(minus[0]),
                V::load(lanes(&plus[1], q)).sub(minus[1]),
                V::load(lanes(&plus[2], q)).sub(minus[2]),
            ];
            let x = [
                V::load(lanes(&xs[0], q)),
                V::load(lanes(&xs[1], q)),
                V::load(lanes(&xs[2], q)),
            ];
            let v = [
                V::load(lanes(&vs[0], q)),
                V::load(lanes(&vs[1], q)),
                V::load(lanes(&vs[2], q)),
            ];
            let m = load_padded::<V>(d.mass, q, count);
            let f = weight_drag_springs(m, d.gravity, d.drag, v, sum);
            let w = load_padded::<V>(d.inv_mass, q, count);
            let a = [f[0].mul(w), f[1].mul(w), f[2].mul(w)];
            let (x_new, v_new) = semi_implicit_euler(x, v, a, dt_lanes);
            // Past the last particle the window stays zero, as the streaming loop's.
            let keep = if count == LANES {
                u8::MAX
            } else {
                (1u8 << count) - 1
            };
            for (new, values) in x_new.into_iter().zip(xs.iter_mut()) {
                new.select(keep).store(chunk_mut(values, q));
            }
            for (new, values) in v_new.into_iter().zip(vs.iter_mut()) {
                new.select(keep).store(chunk_mut(values, q));
            }
        }
    }
}

/// `values[at..at + LANES]` as one chunk.
#[inline(always)]
fn chunk_mut(values: &mut [f64], at: usize) -> &mut [f64; LANES] {
    (&mut values[at..at + LANES]).try_into().expect("a chunk")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::{Workload, setup};
    use crate::physics::collide::ContactParams;
    use crate::physics::forces::Model;
    use crate::physics::particles::State;
    use crate::physics::{Method, MethodParams, SpringKind, Workspace};
    use crate::scene::builder::Builder;

    /// Moves every particle and gives it a velocity (deterministic), so that every spring is
    /// stretched and every damper works.
    fn shaken(mut state: State) -> State {
        let mut seed = 0x5eed_u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for (x, v) in state.x.iter_mut().zip(&mut state.v) {
            *x += 0.01 * DVec3::new(next(), next(), next());
            *v = DVec3::new(next(), next(), next());
        }
        state
    }

    /// The rope of `rope-se`, and a 7×7 cloth with drag (49 particles: a last chunk of one
    /// particle; six offset groups), two corners pinned.
    fn lattices() -> Vec<(Model, State)> {
        let (rope, rope_state) = setup(Workload::RopeSe);
        let mut b = Builder::new();
        let n = 7u32;
        for r in 0..n {
            for c in 0..n {
                b.particle(
                    DVec3::new(f64::from(c) * 0.1, 1.0, f64::from(r) * 0.1),
                    0.02,
                );
            }
        }
        b.pinned[0] = true;
        b.pinned[n as usize - 1] = true;
        let offsets = [(0, 1), (1, 0), (1, 1), (1, -1), (0, 2), (2, 0)];
        for (k, (dr, dc)) in offsets.into_iter().enumerate() {
            for r in 0..n as i32 {
                for c in 0..n as i32 {
                    let (qr, qc) = (r + dr, c + dc);
                    if (0..n as i32).contains(&qr) && (0..n as i32).contains(&qc) {
                        let (p, q) = ((r * n as i32 + c) as u32, (qr * n as i32 + qc) as u32);
                        b.spring(p, q, 500.0 + 100.0 * k as f64, 0.05, SpringKind::Struct);
                    }
                }
            }
        }
        let (cloth, cloth_state) = b.build(DVec3::new(0.0, -9.8, 0.0), 0.3);
        vec![(rope, shaken(rope_state)), (cloth, shaken(cloth_state))]
    }

    fn bits(x: &[DVec3]) -> Vec<[u64; 3]> {
        x.iter()
            .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect()
    }

    #[test]
    fn many_steps_in_one_call_are_the_single_steps_bit_for_bit() {
        let params = MethodParams::default();
        for (model, state) in lattices() {
            for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()) {
                let model = model.clone().with_kernel(kernel);
                let stencil = model.stencil().expect("a lattice");
                let label = format!("{} particles, {kernel:?}", stencil.particles());
                let mut single = state.clone();
                let mut work = Workspace::new();
                for _ in 0..40 {
                    Method::SemiImplicitEuler.step(&model, &mut single, 1e-4, &params, &mut work);
                }
                let mut many = state.clone();
                let dynamics = model.dynamics(true);
                assert!(
                    stencil.semi_implicit_euler_steps(
                        &mut many.x,
                        &mut many.v,
                        &dynamics,
                        1e-4,
                        40
                    ),
                    "{label}: not taken"
                );
                assert_eq!(bits(&many.x), bits(&single.x), "{label}: positions");
                assert_eq!(bits(&many.v), bits(&single.v), "{label}: velocities");
                // The same through `Method::steps`, in two calls.
                let mut via = state.clone();
                let mut work = Workspace::new();
                let evals = Method::SemiImplicitEuler
                    .steps(&model, &mut via, 1e-4, &params, &mut work, 15)
                    + Method::SemiImplicitEuler
                        .steps(&model, &mut via, 1e-4, &params, &mut work, 25);
                assert_eq!(evals, 40);
                assert_eq!(bits(&via.x), bits(&single.x), "{label}: Method::steps");
                assert_eq!(bits(&via.v), bits(&single.v), "{label}: Method::steps");
                // And the state moved.
                assert_ne!(bits(&single.x), bits(&state.x));
            }
        }
    }

    #[test]
    fn large_lattices_and_colliders_are_left_to_the_single_steps() {
        let (jelly, mut state) = setup(Workload::JellySe);
        let before = bits(&state.x);
        let stencil = jelly.stencil().expect("a lattice");
        let dynamics = jelly.dynamics(true);
        assert!(!stencil.semi_implicit_euler_steps(&mut state.x, &mut state.v, &dynamics, 1e-4, 3));
        assert_eq!(bits(&state.x), before);
        let (rope, mut state) = setup(Workload::RopeSe);
        let rope = rope.with_colliders(
            vec![Collider::Sphere {
                center: DVec3::new(0.5, 0.5, 0.0),
                radius: 0.2,
            }],
            ContactParams::course_2021(),
        );
        let stencil = rope.stencil().expect("a lattice");
        let dynamics = rope.dynamics(true);
        assert!(!stencil.semi_implicit_euler_steps(&mut state.x, &mut state.v, &dynamics, 1e-4, 3));
        assert_eq!(bits(&state.x), bits(&setup(Workload::RopeSe).1.x));
    }
}
