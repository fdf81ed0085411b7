//! Arrays of `f64` that start a 64-byte cache line (the parent module's docs, "Aligned
//! arrays").

use crate::physics::lanes::LANES;

/// `f64` values (zeros when made) whose first value starts a 64-byte cache line: a chunk of
/// [`LANES`] values at a multiple of `LANES` is one line, one aligned AVX-512 load (an
/// unaligned chunk spans two lines). The arrays' lengths and margins are multiples of `LANES`,
/// so every chunk at a particle index `front + q` is aligned. Alignment changes no value: the
/// results are the same bits.
#[derive(Debug, Default)]
pub(crate) struct Aligned {
    values: Vec<f64>,
    start: usize,
    len: usize,
}

impl Aligned {
    /// `len` zeros.
    pub(crate) fn zeros(len: usize) -> Aligned {
        let values = vec![0.0; len + LANES];
        let start = values.as_ptr().align_offset(64).min(LANES);
        Aligned { values, start, len }
    }
}

impl Clone for Aligned {
    fn clone(&self) -> Aligned {
        let mut copy = Aligned::zeros(self.len);
        copy.copy_from_slice(self);
        copy
    }
}

impl std::ops::Deref for Aligned {
    type Target = [f64];
    #[inline(always)]
    fn deref(&self) -> &[f64] {
        // SAFETY: `start + len ≤ values.len()` (`zeros`), and `values` never changes length.
        unsafe { std::slice::from_raw_parts(self.values.as_ptr().add(self.start), self.len) }
    }
}

impl std::ops::DerefMut for Aligned {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [f64] {
        // SAFETY: as `deref`.
        unsafe {
            std::slice::from_raw_parts_mut(self.values.as_mut_ptr().add(self.start), self.len)
        }
    }
}
