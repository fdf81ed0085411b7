//! The fast engine: everything SIMD, threaded or fused, behind one seam.
//!
//! The teaching files (`springs.rs`, `forces.rs`, `integrators/*.rs`, `constraints.rs`) hold the
//! physics as the formulas write it. On a lattice they hand the same arithmetic to this module,
//! one call per stage, and get the same numbers back (bit for bit, tested per method):
//!
//! - [`stencil`]: springs grouped by index offset, one fused pass per stage (force, acceleration,
//!   every explicit method's update, contact force, dissipated power), split between threads;
//!   its kernels (portable, AVX2, AVX-512) are chosen at run time. `stencil/small.rs` takes many
//!   semi-implicit Euler steps of a small lattice in one call, `stencil/team.rs` runs many passes
//!   as one pool job, `stencil/ceiling.rs` measures the machine's ceiling for `springlab bench`.
//! - [`lanes`]: the one lane abstraction over the intrinsics (`Plain`, `Avx2`, `Avx512`).
//! - [`pool`]: the persistent worker pool (one thread per core).
//! - `implicit_lattice`: implicit Euler's Newton step on a lattice in structure-of-arrays form.
//! - `implicit_constraint`: a contact constraint of implicit Euler's solve (both paths read it).
//! - `chain`: Verlet's red-black projection of a chain, eight rods at a time.
//! - `bounds`: the boxes of the collision response's broad phase, eight points at a time.
//! - `healthy`: the divergence check's quick pass, eight particles at a time.
//! - `marks`: the response's broad phase point by point (sphere, bowl, floor with a hole),
//!   eight points at a time.
//! - `energy`: the kinetic and gravitational terms of Verlet's energy accounting, a block of
//!   particles at a time with the widest vectors.
//! - `ledger`: the kinetic energy the collision response's budget pays from, a block of
//!   particles at a time with the widest vectors, added in particle order.
//! - `elastic`: the elastic energy `Σ ½ k (L - L0)²` of `physics/energy.rs`, a block of springs
//!   at a time with the widest vectors, added in spring order.
//! - [`quadratic`]: the stability study's sum over springs (a perturbation's elastic energy), a
//!   block of springs at a time with the widest vectors.
//!
//! This is the only part of the crate allowed `unsafe` (the intrinsics and the pool's shared
//! buffers); `Cargo.toml` denies it everywhere else.
#![allow(unsafe_code)]

/// Defines `$name(args…)`: `$body::<V>` on the widest [`lanes::Lanes`] of a kernel, through an
/// AVX-512 and an AVX2 instance, each compiled with its target feature so that the inlined body
/// runs on those registers. `on_lanes!(vis name, body, (args) -> ret)` takes the CPU's best
/// ([`stencil::Kernel::best`]); `on_lanes!(vis name(kernel), body, (args) -> ret)` adds a first
/// parameter `kernel: Kernel`, which must be one this CPU has (as a stencil's kernel and
/// `Kernel::best` are). With `plain body` the body is not generic (scalar code the compiler
/// vectorises): each instance compiles it with its target feature.
macro_rules! on_lanes {
    ($vis:vis $name:ident(kernel), plain $body:ident, $sig:tt -> $ret:ty) => {
        on_lanes!(@kernel $vis $name, [$body], [$body], [$body], $sig -> $ret);
    };
    ($vis:vis $name:ident, plain $body:ident, $sig:tt -> $ret:ty) => {
        on_lanes!(@best $vis $name, [$body], [$body], [$body], $sig -> $ret);
    };
    ($vis:vis $name:ident(kernel), $body:ident, $sig:tt -> $ret:ty) => {
        on_lanes!(
            @kernel $vis $name,
            [$body::<$crate::physics::fast::lanes::Avx512>],
            [$body::<$crate::physics::fast::lanes::Avx2>],
            [$body::<$crate::physics::fast::lanes::Plain>],
            $sig -> $ret
        );
    };
    ($vis:vis $name:ident, $body:ident, $sig:tt -> $ret:ty) => {
        on_lanes!(
            @best $vis $name,
            [$body::<$crate::physics::fast::lanes::Avx512>],
            [$body::<$crate::physics::fast::lanes::Avx2>],
            [$body::<$crate::physics::fast::lanes::Plain>],
            $sig -> $ret
        );
    };
    (@kernel $vis:vis $name:ident, $wide:tt, $narrow:tt, $plain:tt,
        ($($arg:ident: $ty:ty),*) -> $ret:ty) => {
        #[allow(clippy::too_many_arguments)]
        $vis fn $name(kernel: $crate::physics::fast::stencil::Kernel, $($arg: $ty),*) -> $ret {
            on_lanes!(@dispatch kernel, $wide, $narrow, $plain, ($($arg: $ty),*) -> $ret)
        }
    };
    (@best $vis:vis $name:ident, $wide:tt, $narrow:tt, $plain:tt,
        ($($arg:ident: $ty:ty),*) -> $ret:ty) => {
        #[allow(clippy::too_many_arguments)]
        $vis fn $name($($arg: $ty),*) -> $ret {
            on_lanes!(
                @dispatch $crate::physics::fast::stencil::Kernel::best(),
                $wide, $narrow, $plain,
                ($($arg: $ty),*) -> $ret
            )
        }
    };
    (@dispatch $kernel:expr, [$($wide:tt)*], [$($narrow:tt)*], [$($plain:tt)*],
        ($($arg:ident: $ty:ty),*) -> $ret:ty) => {{
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f")]
        #[allow(clippy::too_many_arguments)]
        fn avx512($($arg: $ty),*) -> $ret {
            $($wide)*($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        #[allow(clippy::too_many_arguments)]
        fn avx2($($arg: $ty),*) -> $ret {
            $($narrow)*($($arg),*)
        }

        match $kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the kernel is one this CPU has (macro docs).
            $crate::physics::fast::stencil::Kernel::Avx512 => unsafe { avx512($($arg),*) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            $crate::physics::fast::stencil::Kernel::Avx2 => unsafe { avx2($($arg),*) },
            _ => $($plain)*($($arg),*),
        }
    }};
}

pub(crate) mod bounds;
pub(crate) mod chain;
pub(crate) mod elastic;
pub(crate) mod energy;
pub(crate) mod healthy;
pub(crate) mod implicit_constraint;
pub(crate) mod implicit_lattice;
pub(crate) mod lanes;
pub(crate) mod ledger;
pub(crate) mod marks;
pub mod pool;
pub mod quadratic;
pub mod stencil;
pub(crate) mod xpbd;
