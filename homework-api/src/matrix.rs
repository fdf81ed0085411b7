//! A small dense [`Matrix`] with a linear solver, for the backward Euler task, and
//! [`flatten`] / [`unflatten`] between vectors and one column of numbers.

use std::ops::{Index, IndexMut};

use crate::DVec3;

/// A dense square matrix of `f64`, row-major; index it with `m[(row, column)]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Matrix {
    size: usize,
    data: Vec<f64>,
}

impl Matrix {
    /// The `size × size` zero matrix.
    #[must_use]
    pub fn zeros(size: usize) -> Matrix {
        Matrix {
            size,
            data: vec![0.0; size * size],
        }
    }

    /// The `size × size` identity.
    #[must_use]
    pub fn identity(size: usize) -> Matrix {
        let mut m = Matrix::zeros(size);
        for i in 0..size {
            m[(i, i)] = 1.0;
        }
        m
    }

    /// A matrix from its rows, one after the other (`values.len()` must be `size²`).
    #[must_use]
    pub fn from_row_major(size: usize, values: Vec<f64>) -> Option<Matrix> {
        (values.len() == size * size).then_some(Matrix { size, data: values })
    }

    /// The entries, row after row.
    #[must_use]
    pub fn as_row_major(&self) -> &[f64] {
        &self.data
    }

    /// Number of rows (and of columns).
    #[must_use]
    pub fn size(&self) -> usize {
        self.size
    }

    /// The product `M y`.
    ///
    /// # Panics
    /// If `y.len()` differs from the size.
    #[must_use]
    pub fn mul_vec(&self, y: &[f64]) -> Vec<f64> {
        assert_eq!(y.len(), self.size, "Matrix::mul_vec: wrong vector length");
        (0..self.size)
            .map(|i| {
                let row = &self.data[i * self.size..(i + 1) * self.size];
                row.iter().zip(y).map(|(m, y)| m * y).sum()
            })
            .collect()
    }

    /// Solves `M y = b` by Gaussian elimination with partial pivoting; `None` when the matrix is
    /// singular (a pivot is zero or not finite) or `b` has the wrong length.
    #[must_use]
    pub fn solve(&self, b: &[f64]) -> Option<Vec<f64>> {
        let n = self.size;
        if b.len() != n {
            return None;
        }
        let mut m = self.data.clone();
        let mut y = b.to_vec();
        for col in 0..n {
            // Pivot: the largest entry of the column on or below the diagonal.
            let pivot =
                (col..n).max_by(|&p, &q| m[p * n + col].abs().total_cmp(&m[q * n + col].abs()))?;
            let p = m[pivot * n + col];
            if p == 0.0 || !p.is_finite() {
                return None;
            }
            if pivot != col {
                for k in 0..n {
                    m.swap(col * n + k, pivot * n + k);
                }
                y.swap(col, pivot);
            }
            // Eliminate below: row_r -= (m_rc / m_cc) row_c.
            for r in col + 1..n {
                let factor = m[r * n + col] / p;
                if factor != 0.0 {
                    for k in col..n {
                        m[r * n + k] -= factor * m[col * n + k];
                    }
                    y[r] -= factor * y[col];
                }
            }
        }
        // Back substitution.
        for col in (0..n).rev() {
            let mut s = y[col];
            for k in col + 1..n {
                s -= m[col * n + k] * y[k];
            }
            y[col] = s / m[col * n + col];
        }
        y.iter().all(|v| v.is_finite()).then_some(y)
    }
}

impl Index<(usize, usize)> for Matrix {
    type Output = f64;

    fn index(&self, (row, column): (usize, usize)) -> &f64 {
        assert!(
            row < self.size && column < self.size,
            "Matrix index ({row}, {column}) out of range for size {}",
            self.size
        );
        &self.data[row * self.size + column]
    }
}

impl IndexMut<(usize, usize)> for Matrix {
    fn index_mut(&mut self, (row, column): (usize, usize)) -> &mut f64 {
        assert!(
            row < self.size && column < self.size,
            "Matrix index ({row}, {column}) out of range for size {}",
            self.size
        );
        &mut self.data[row * self.size + column]
    }
}

/// `[x0, y0, z0, x1, y1, z1, ...]`: vectors as one column, the layout of [`Matrix`] rows.
#[must_use]
pub fn flatten(vectors: &[DVec3]) -> Vec<f64> {
    vectors.iter().flat_map(|v| v.to_array()).collect()
}

/// The inverse of [`flatten`]; a trailing incomplete triple is dropped.
#[must_use]
pub fn unflatten(values: &[f64]) -> Vec<DVec3> {
    values
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::Matrix;

    #[test]
    fn solve_inverts_mul_vec() {
        let m = Matrix::from_row_major(3, vec![4.0, 1.0, 0.0, 1.0, 3.0, -1.0, 0.0, -1.0, 2.0])
            .expect("3x3");
        let y = [1.0, -2.0, 0.5];
        let b = m.mul_vec(&y);
        let solved = m.solve(&b).expect("regular");
        for (s, y) in solved.iter().zip(y) {
            assert!((s - y).abs() < 1e-14);
        }
        assert!(Matrix::zeros(2).solve(&[1.0, 1.0]).is_none());
    }
}
