//! Small dense square matrices for the adding-doubling operators (n = 2-64 streams): products, sums and linear solves
//! by LU decomposition with partial pivoting (Golub & Van Loan, "Matrix Computations", algorithm 3.4.1).
//!
//! Hand-written rather than a linear-algebra crate: the operators are at most 64 x 64, the solver needs four
//! operations, and a row-major `Vec<f64>` with the inner loop over contiguous rows (which the compiler vectorises)
//! is what a doubling step spends its time in (benches/adding_doubling.rs measures it).

use std::ops::{Index, IndexMut};

/// An `n x n` matrix, row-major.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Matrix {
    n: usize,
    a: Vec<f64>,
}

impl Matrix {
    pub(crate) fn zeros(n: usize) -> Matrix {
        Matrix { n, a: vec![0.0; n * n] }
    }

    pub(crate) fn identity(n: usize) -> Matrix {
        let mut m = Matrix::zeros(n);
        for i in 0..n {
            m.a[i * n + i] = 1.0;
        }
        m
    }

    pub(crate) fn n(&self) -> usize {
        self.n
    }

    pub(crate) fn fill(&mut self, value: f64) {
        self.a.fill(value);
    }

    /// `self * other`.
    pub(crate) fn mul(&self, other: &Matrix) -> Matrix {
        let n = self.n;
        let mut out = Matrix::zeros(n);
        for i in 0..n {
            let row = &mut out.a[i * n..(i + 1) * n];
            for k in 0..n {
                let aik = self.a[i * n + k];
                if aik == 0.0 {
                    continue;
                }
                let other_row = &other.a[k * n..(k + 1) * n];
                for (o, b) in row.iter_mut().zip(other_row) {
                    *o += aik * b;
                }
            }
        }
        out
    }

    pub(crate) fn plus(&self, other: &Matrix) -> Matrix {
        Matrix { n: self.n, a: self.a.iter().zip(&other.a).map(|(x, y)| x + y).collect() }
    }

    pub(crate) fn minus(&self, other: &Matrix) -> Matrix {
        Matrix { n: self.n, a: self.a.iter().zip(&other.a).map(|(x, y)| x - y).collect() }
    }

    /// `self += scale * other`.
    pub(crate) fn add_scaled(&mut self, other: &Matrix, scale: f64) {
        for (x, y) in self.a.iter_mut().zip(&other.a) {
            *x += scale * y;
        }
    }

    /// The largest absolute difference of two elements.
    pub(crate) fn max_abs_difference(&self, other: &Matrix) -> f64 {
        self.a.iter().zip(&other.a).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
    }

    /// `self^-1 rhs`. A singular matrix (a zero pivot: only a non-absorbing, infinitely thick layer comes near one,
    /// and the callers stop short of it) gives non-finite values, which the callers' range checks catch.
    pub(crate) fn solve(&self, rhs: &Matrix) -> Matrix {
        let lu = Lu::of(self);
        let n = self.n;
        let mut x = rhs.clone();
        lu.solve_in_place(&mut x.a, n);
        x
    }

    /// `self^-1 rhs` for a vector.
    pub(crate) fn solve_vector(&self, rhs: &[f64]) -> Vec<f64> {
        let lu = Lu::of(self);
        let mut x = rhs.to_vec();
        lu.solve_in_place(&mut x, 1);
        x
    }
}

impl Index<(usize, usize)> for Matrix {
    type Output = f64;
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        &self.a[i * self.n + j]
    }
}

impl IndexMut<(usize, usize)> for Matrix {
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        &mut self.a[i * self.n + j]
    }
}

/// `P A = L U` packed in one matrix (unit lower L below the diagonal), with the row permutation.
struct Lu {
    n: usize,
    lu: Vec<f64>,
    perm: Vec<usize>,
}

impl Lu {
    fn of(m: &Matrix) -> Lu {
        let n = m.n;
        let mut lu = m.a.clone();
        let mut perm: Vec<usize> = (0..n).collect();
        for k in 0..n {
            let pivot = (k..n).max_by(|&i, &j| lu[i * n + k].abs().total_cmp(&lu[j * n + k].abs())).unwrap_or(k);
            if pivot != k {
                for j in 0..n {
                    lu.swap(k * n + j, pivot * n + j);
                }
                perm.swap(k, pivot);
            }
            let d = lu[k * n + k];
            for i in k + 1..n {
                let f = lu[i * n + k] / d;
                lu[i * n + k] = f;
                if f != 0.0 {
                    let (upper, lower) = lu.split_at_mut(i * n);
                    let pivot_row = &upper[k * n + k + 1..k * n + n];
                    for (x, p) in lower[k + 1..n].iter_mut().zip(pivot_row) {
                        *x -= f * p;
                    }
                }
            }
        }
        Lu { n, lu, perm }
    }

    /// Overwrite `b` (n rows of `cols` values, row-major) with `A^-1 b`.
    fn solve_in_place(&self, b: &mut [f64], cols: usize) {
        let n = self.n;
        let permuted: Vec<f64> = self.perm.iter().flat_map(|&p| b[p * cols..(p + 1) * cols].to_vec()).collect();
        b.copy_from_slice(&permuted);
        // Forward: L y = P b.
        for i in 0..n {
            for k in 0..i {
                let l = self.lu[i * n + k];
                if l != 0.0 {
                    let (done, rest) = b.split_at_mut(i * cols);
                    for (x, y) in rest[..cols].iter_mut().zip(&done[k * cols..(k + 1) * cols]) {
                        *x -= l * y;
                    }
                }
            }
        }
        // Back: U x = y.
        for i in (0..n).rev() {
            for k in i + 1..n {
                let u = self.lu[i * n + k];
                if u != 0.0 {
                    let (head, tail) = b.split_at_mut(k * cols);
                    for (x, y) in head[i * cols..(i + 1) * cols].iter_mut().zip(&tail[..cols]) {
                        *x -= u * y;
                    }
                }
            }
            let d = self.lu[i * n + i];
            for x in &mut b[i * cols..(i + 1) * cols] {
                *x /= d;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_inverts_a_product() {
        let n = 5;
        let mut a = Matrix::zeros(n);
        let mut b = Matrix::zeros(n);
        for i in 0..n {
            for j in 0..n {
                // A pivoting case: a zero leading element.
                a[(i, j)] = if i == 0 && j == 0 { 0.0 } else { ((i * 7 + j * 3) % 11) as f64 - 4.0 };
                b[(i, j)] = (i + 2 * j) as f64;
            }
        }
        let x = a.solve(&b);
        let back = a.mul(&x);
        assert!(back.max_abs_difference(&b) < 1e-10, "{back:?} vs {b:?}");
        let v = a.solve_vector(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        for i in 0..n {
            let s: f64 = (0..n).map(|j| a[(i, j)] * v[j]).sum();
            assert!((s - (i + 1) as f64).abs() < 1e-10, "row {i}: {s}");
        }
    }
}
