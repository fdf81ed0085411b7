//! The ceiling of the streaming loop: how many springs per second one thread's spring kernel
//! evaluates when its operands are already in the first-level cache, so that nothing but the
//! kernel's own arithmetic (and its loads from that cache) sets the rate:
//!
//! ```text
//! ceiling = 8 c / t      (springs/s per thread)
//! ```
//! where `c` is the number of chunks of eight springs evaluated (the same two chunks of a
//! 40-particle rope over and over, each time read again from memory) and `t` the time they
//! took (s). A pass over a lattice does more (the window's copy, the second ends' forces through
//! the rings, the update and its stores, the caches below the first), so its springs·steps/s
//! divided by this rate and by the threads is the fraction of the machine it uses.
//! `springlab bench` prints it; `cargo bench -p springlab-benches --bench workloads` times [`Rope::evaluate`].

use std::time::Instant;

use super::passes::Window;
#[allow(clippy::wildcard_imports)]
use super::*;

/// Particles of the rope: enough springs for a stencil.
const ROPE: usize = 40;

/// A rope of [`ROPE`] particles along x (springs of rest length 1 m between neighbours,
/// stretched and moving), its one group and its particles as structure of arrays: what
/// [`Rope::evaluate`] runs the kernels on.
pub struct Rope {
    stencil: Stencil,
    x: [Vec<f64>; 3],
    v: [Vec<f64>; 3],
}

/// The rope's springs: neighbours `(i, i + 1)`, `L0` 1 m, `k` 100 N/m, `k_d` 0.1 N·s/m.
fn springs() -> Vec<Spring> {
    (0..ROPE as u32 - 1)
        .map(|i| Spring {
            a: i,
            b: i + 1,
            rest_length: 1.0,
            stiffness: 100.0,
            damping: 0.1,
            kind: crate::physics::springs::SpringKind::Struct,
        })
        .collect()
}

impl Default for Rope {
    fn default() -> Rope {
        let stencil = Stencil::detect(ROPE, &springs()).expect("a rope is a lattice");
        let component = |f: fn(usize) -> f64| {
            let mut a = vec![0.0; ROPE.next_multiple_of(LANES)];
            for (i, value) in a.iter_mut().enumerate().take(ROPE) {
                *value = f(i);
            }
            a
        };
        Rope {
            stencil,
            x: [
                component(|i| 1.1 * i as f64),
                component(|i| 0.01 * (i % 3) as f64),
                component(|_| 0.0),
            ],
            v: [
                component(|i| 0.1 * (i % 5) as f64),
                component(|_| -0.2),
                component(|i| 0.05 * (i % 2) as f64),
            ],
        }
    }
}

impl Rope {
    /// Evaluates `chunks` chunks of eight springs with `kernel` (the chunks at particles 0 and
    /// 8, in turn); returns the sum of their forces' x components (N), so that none of the work
    /// can be left out. Each chunk's ends are loaded again from the rope's arrays.
    ///
    /// # Panics
    /// When this CPU cannot run `kernel`.
    #[must_use]
    pub fn evaluate(&self, kernel: Kernel, chunks: u64) -> f64 {
        assert!(kernel.is_available(), "{kernel:?} is not available here");
        let g = &self.stencil.groups[0];
        let w = Window {
            x: [&self.x[0], &self.x[1], &self.x[2]],
            v: [&self.v[0], &self.v[1], &self.v[2]],
        };
        match kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: available (asserted above).
            Kernel::Avx512 => unsafe { chunks_avx512(g, &w, chunks) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: available (asserted above).
            Kernel::Avx2 => unsafe { chunks_avx2(g, &w, chunks) },
            _ => chunks_body::<Plain>(g, &w, chunks, |g, first, w, i, p| {
                kernels::springs_exact::<Plain>(g, first, w, i, p)
            }),
        }
    }
}

/// The springs per second of one thread of `kernel` on this machine: the best of three runs of
/// [`Rope::evaluate`] of about 5 ms each.
#[must_use]
pub fn ceiling(kernel: Kernel) -> f64 {
    // About 5 ms at 2e9 springs/s.
    const CHUNKS: u64 = 1_250_000;
    let rope = Rope::default();
    (0..3)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(rope.evaluate(kernel, CHUNKS));
            8.0 * CHUNKS as f64 / start.elapsed().as_secs_f64()
        })
        .fold(0.0, f64::max)
}

#[inline(always)]
fn chunks_body<V: Lanes>(
    g: &Group,
    w: &Window,
    chunks: u64,
    springs: impl Fn(&Group, &[V; 6], &Window, usize, usize) -> (passes::Forces<V>, V),
) -> f64 {
    let mut sum = V::zero();
    for c in 0..chunks {
        // Which chunk is opaque to the compiler, so each is read and computed again (nothing is
        // hoisted out of the loop).
        let i = std::hint::black_box((c as usize & 1) * LANES);
        let (f, _) = springs(g, &w.first_ends::<V>(i), w, i, i);
        sum = sum.add(f[0]);
    }
    let mut values = [0.0; LANES];
    sum.store(&mut values);
    values.iter().sum()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn chunks_avx512(g: &Group, w: &Window, chunks: u64) -> f64 {
    chunks_body::<Avx512>(
        g,
        w,
        chunks,
        #[inline(always)]
        |g, first, w, i, p| {
            // SAFETY: AVX-512F (this function's feature); the chunks at 0 and 8 lie inside the
            // window of 40 values and the group's arrays.
            unsafe { kernels::springs_avx512(g, first, w, i, p) }
        },
    )
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn chunks_avx2(g: &Group, w: &Window, chunks: u64) -> f64 {
    chunks_body::<Avx2>(
        g,
        w,
        chunks,
        #[inline(always)]
        #[allow(clippy::redundant_closure)]
        |g, first, w, i, p| kernels::springs_exact::<Avx2>(g, first, w, i, p),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kernel_gives_the_ropes_forces_for_every_chunk() {
        // The x components of the forces on the first ends of springs 0..16, summed, times the
        // number of times each chunk was evaluated: the spring list's own forces.
        let rope = Rope::default();
        let springs = springs();
        let at = |a: &[Vec<f64>; 3], i: usize| DVec3::new(a[0][i], a[1][i], a[2][i]);
        let x: Vec<DVec3> = (0..ROPE).map(|i| at(&rope.x, i)).collect();
        let v: Vec<DVec3> = (0..ROPE).map(|i| at(&rope.v, i)).collect();
        let per_pair: f64 = springs[..16].iter().map(|s| s.force_on_a(&x, &v).x).sum();
        for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()) {
            let sum = rope.evaluate(kernel, 10);
            assert!(
                (sum - 5.0 * per_pair).abs() <= 1e-12 * per_pair.abs(),
                "{kernel:?}: {sum} vs {}",
                5.0 * per_pair
            );
        }
    }
}
