//! Small dense square matrices for the adding-doubling operators (n = 4-64 streams): products, sums and linear solves
//! by Gaussian elimination with partial pivoting (Golub & Van Loan, "Matrix Computations", algorithm 3.4.1).
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

    pub(crate) fn diagonal(values: &[f64]) -> Matrix {
        let n = values.len();
        let mut m = Matrix::zeros(n);
        for (i, v) in values.iter().enumerate() {
            m.a[i * n + i] = *v;
        }
        m
    }

    pub(crate) fn transpose(&self) -> Matrix {
        let n = self.n;
        let mut t = Matrix::zeros(n);
        for i in 0..n {
            for j in 0..n {
                t.a[j * n + i] = self.a[i * n + j];
            }
        }
        t
    }

    /// `diag(d) * self`: row i scaled by `d[i]`.
    pub(crate) fn scale_rows(&self, d: &[f64]) -> Matrix {
        let n = self.n;
        let mut m = self.clone();
        for (row, di) in m.a.chunks_exact_mut(n).zip(d) {
            row.iter_mut().for_each(|x| *x *= di);
        }
        m
    }

    /// `self * v`.
    pub(crate) fn mul_vector(&self, v: &[f64]) -> Vec<f64> {
        self.a.chunks_exact(self.n).map(|row| row.iter().zip(v).map(|(x, y)| x * y).sum()).collect()
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
        match n {
            4 => mul_fixed::<4>(&self.a, &other.a, &mut out.a),
            6 => mul_fixed::<6>(&self.a, &other.a, &mut out.a),
            8 => mul_fixed::<8>(&self.a, &other.a, &mut out.a),
            10 => mul_fixed::<10>(&self.a, &other.a, &mut out.a),
            12 => mul_fixed::<12>(&self.a, &other.a, &mut out.a),
            16 => mul_fixed::<16>(&self.a, &other.a, &mut out.a),
            32 => mul_fixed::<32>(&self.a, &other.a, &mut out.a),
            _ => {
                for i in 0..n {
                    let row = &mut out.a[i * n..(i + 1) * n];
                    for k in 0..n {
                        let aik = self.a[i * n + k];
                        let other_row = &other.a[k * n..(k + 1) * n];
                        for (o, b) in row.iter_mut().zip(other_row) {
                            *o += aik * b;
                        }
                    }
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
        let mut x = rhs.clone();
        solve_in_place(self.a.clone(), self.n, &mut x.a, self.n);
        x
    }

    /// `self^-1 rhs` for a vector.
    pub(crate) fn solve_vector(&self, rhs: &[f64]) -> Vec<f64> {
        let mut x = rhs.to_vec();
        solve_in_place(self.a.clone(), self.n, &mut x, 1);
        x
    }
}

/// Overwrite `b` (n rows of `cols` values, row-major) with `A^-1 b`: Gaussian elimination with partial pivoting on
/// `[A | b]` (the row swaps applied to both as they happen), then back substitution.
fn solve_in_place(mut a: Vec<f64>, n: usize, b: &mut [f64], cols: usize) {
    for k in 0..n {
        let pivot = (k..n).max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs())).unwrap_or(k);
        if pivot != k {
            for j in k..n {
                a.swap(k * n + j, pivot * n + j);
            }
            for j in 0..cols {
                b.swap(k * cols + j, pivot * cols + j);
            }
        }
        let d = a[k * n + k];
        let (top, bottom) = a.split_at_mut((k + 1) * n);
        let pivot_row = &top[k * n + k + 1..];
        let (b_top, b_bottom) = b.split_at_mut((k + 1) * cols);
        let b_pivot = &b_top[k * cols..];
        for (row, b_row) in bottom.chunks_exact_mut(n).zip(b_bottom.chunks_exact_mut(cols)) {
            let f = row[k] / d;
            if f != 0.0 {
                for (x, p) in row[k + 1..].iter_mut().zip(pivot_row) {
                    *x -= f * p;
                }
                for (x, p) in b_row.iter_mut().zip(b_pivot) {
                    *x -= f * p;
                }
            }
        }
    }
    for i in (0..n).rev() {
        let (head, tail) = b.split_at_mut((i + 1) * cols);
        let b_row = &mut head[i * cols..];
        for (k, done) in (i + 1..n).zip(tail.chunks_exact(cols)) {
            let u = a[i * n + k];
            for (x, y) in b_row.iter_mut().zip(done) {
                *x -= u * y;
            }
        }
        let d = a[i * n + i];
        for x in b_row.iter_mut() {
            *x /= d;
        }
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

/// `out = a b` for `N x N` row-major matrices, the size known at compile time: each output row is accumulated in
/// registers (the levels' stream counts 4, 10 and 32 and the even counts near them take this path; measured 2-3 times
/// faster than the loop over a run-time size, `cargo bench --bench adding_doubling`).
fn mul_fixed<const N: usize>(a: &[f64], b: &[f64], out: &mut [f64]) {
    for (out_row, a_row) in out.chunks_exact_mut(N).zip(a.chunks_exact(N)) {
        let mut acc = [0.0; N];
        for (aik, b_row) in a_row.iter().zip(b.chunks_exact(N)) {
            for (x, y) in acc.iter_mut().zip(b_row) {
                *x += aik * y;
            }
        }
        out_row.copy_from_slice(&acc);
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
