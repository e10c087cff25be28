//! Tree-sparse algebra of a multibody's joint-space mass matrix.
//!
//! Patch: a file of the `grasp` project, not part of upstream rapier 0.36.1; see
//! `vendor/README.md` of that project.
//!
//! In a kinematic tree the mass matrix `M` has an entry `(a, b)` only where DoF `a` is an
//! ancestor of DoF `b` or the reverse, because the body Jacobian of a link is zero outside
//! the DoFs of the link and of its ancestors. With the DoFs in topological order (every
//! ancestor before its descendants, as rapier assembles them) `M` factors as
//! `M = Lᵀ D L`, `L` unit lower triangular with the same sparsity (no fill-in), by
//! eliminating the DoFs from the leaves to the root. This is MuJoCo's `mj_factorM` /
//! `mj_solveM`: a factorisation costs about `Σ depth²` and a solve `2 Σ depth` instead of
//! the dense LU's `n³/3` and `n²`. For a 25-DoF hand whose fingers hang off a 3-DoF arm
//! (depth at most 8), a solve is several times cheaper, and each contact, limit, motor and
//! coupling row of the solver does one.

use crate::alloc_prelude::*;
use crate::math::Real;
use na::{DMatrix, Dim, Dyn, LU, Matrix, StorageMut};

/// Marks a DoF without a parent DoF (the first DoF of a root).
pub const NO_PARENT: usize = usize::MAX;

/// A factorisation of the augmented mass matrix with a dense fallback.
#[derive(Clone, Debug)]
pub enum MassFactor {
    /// nalgebra's dense LU (multibodies with kinematic DoFs, or a matrix the tree
    /// factorisation refused).
    Dense(LU<Real, Dyn, Dyn>),
    /// The tree-sparse `Lᵀ D L`.
    Tree(TreeLdl),
}

impl MassFactor {
    /// The factor of the empty matrix.
    pub fn empty() -> Self {
        MassFactor::Dense(LU::new(DMatrix::zeros(0, 0)))
    }

    /// Factors the symmetric `m` with the tree structure `parent` (the parent DoF of each
    /// DoF, or [`NO_PARENT`]) when `parent` is given and describes a topological order,
    /// falling back to a dense LU otherwise (or when a pivot is not positive).
    /// Only the leading `dim x dim` block of `m` is factored; the tree factorisation
    /// needs the whole matrix (`dim == m.nrows()`).
    pub fn new(m: &DMatrix<Real>, dim: usize, parent: Option<&[usize]>) -> Self {
        Self::with(m, dim, parent, TreeLdl::new)
    }

    /// [`MassFactor::new`] for a matrix that has the tree's sparsity but is not symmetric
    /// (the acceleration matrix, which carries Coriolis and gyroscopic terms): a tree
    /// `U D L` without pivoting, or the dense LU when a pivot is not positive.
    pub fn new_unsymmetric(m: &DMatrix<Real>, dim: usize, parent: Option<&[usize]>) -> Self {
        Self::with(m, dim, parent, TreeLdl::new_unsymmetric)
    }

    fn with(
        m: &DMatrix<Real>,
        dim: usize,
        parent: Option<&[usize]>,
        tree_factor: fn(&DMatrix<Real>, &[usize]) -> Option<TreeLdl>,
    ) -> Self {
        let tree = parent.filter(|_| dim == m.nrows() && dim == m.ncols());
        match tree.and_then(|p| tree_factor(m, p)) {
            Some(t) => MassFactor::Tree(t),
            None => MassFactor::Dense(LU::new(m.view((0, 0), (dim, dim)).into_owned())),
        }
    }

    /// The tree factor, if this is one.
    pub fn as_tree(&self) -> Option<&TreeLdl> {
        match self {
            MassFactor::Tree(t) => Some(t),
            MassFactor::Dense(_) => None,
        }
    }

    /// Solves `M x = b` in place for every column of `b`. Returns false when the dense
    /// factor is singular (as [`LU::solve_mut`]).
    pub fn solve_mut<R2: Dim, C2: Dim, S2>(&self, b: &mut Matrix<Real, R2, C2, S2>) -> bool
    where
        S2: StorageMut<Real, R2, C2>,
        na::constraint::ShapeConstraint: na::constraint::SameNumberOfRows<R2, Dyn>,
    {
        match self {
            MassFactor::Dense(lu) => lu.solve_mut(b),
            MassFactor::Tree(t) => {
                for c in 0..b.ncols() {
                    t.solve_column(&mut b.column_mut(c));
                }
                true
            }
        }
    }
}

/// `M = Lᵀ D L` of a tree-sparse symmetric positive-definite matrix, or `M = U D L` of
/// one that is not symmetric (`U` unit upper triangular with the transposed sparsity
/// of `L`).
#[derive(Clone, Debug)]
pub struct TreeLdl {
    /// `D⁻¹` (the inverse pivots).
    inv_diag: Vec<Real>,
    /// Row `k` of `L` below the diagonal: the columns `cols[start[k]..start[k + 1]]` (`k`'s
    /// ancestors, nearest first) with the values `vals[..]` at the same positions.
    start: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<Real>,
    /// Column `k` of `U` above the diagonal at the positions of row `k` of `L`; `None`
    /// for a symmetric matrix (`U = Lᵀ`).
    upper: Option<Vec<Real>>,
}

impl TreeLdl {
    /// Row `k` of `L`'s sparsity (`start`, `cols`) with `m`'s entries `(k, i)` and
    /// `(i, k)` for `k`'s ancestors `i`; `None` if `parent` is not a topological order of
    /// `m`'s size.
    #[allow(clippy::type_complexity)]
    fn gather(
        m: &DMatrix<Real>,
        parent: &[usize],
    ) -> Option<(Vec<usize>, Vec<usize>, Vec<Real>, Vec<Real>)> {
        let n = m.nrows();
        if m.ncols() != n || parent.len() != n {
            return None;
        }
        if parent
            .iter()
            .enumerate()
            .any(|(k, &p)| p != NO_PARENT && p >= k)
        {
            return None;
        }
        let mut nnz = 0;
        for k in 0..n {
            let mut i = parent[k];
            while i != NO_PARENT {
                nnz += 1;
                i = parent[i];
            }
        }
        let mut start = Vec::with_capacity(n + 1);
        let mut cols = Vec::with_capacity(nnz);
        let mut lower = Vec::with_capacity(nnz);
        let mut upper = Vec::with_capacity(nnz);
        for k in 0..n {
            start.push(cols.len());
            let mut i = parent[k];
            while i != NO_PARENT {
                cols.push(i);
                lower.push(m[(k, i)]);
                upper.push(m[(i, k)]);
                i = parent[i];
            }
        }
        start.push(cols.len());
        Some((start, cols, lower, upper))
    }

    /// Factors `m`, which has the tree's sparsity but need not be symmetric, as `U D L`
    /// along `parent`, without pivoting; `None` if `parent` is not a topological order of
    /// `m`'s size or a pivot is not positive and finite.
    pub fn new_unsymmetric(m: &DMatrix<Real>, parent: &[usize]) -> Option<TreeLdl> {
        let n = m.nrows();
        let (start, cols, mut lower, mut upper) = Self::gather(m, parent)?;
        let mut diag: Vec<Real> = (0..n).map(|k| m[(k, k)]).collect();
        // As in `new`, from the leaves up: eliminating `k` subtracts
        // `m(i, k) m(k, j) / d_k` from every `m(i, j)` with `i`, `j` ancestors of `k`.
        for k in (0..n).rev() {
            let dk = diag[k];
            if !(dk > 0.0 && dk.is_finite()) {
                return None;
            }
            let (sk, ek) = (start[k], start[k + 1]);
            for a in sk..ek {
                let i = cols[a];
                let lki = lower[a] / dk;
                let uik = upper[a] / dk;
                diag[i] -= upper[a] * lki;
                let si = start[i];
                let (lhead, ltail) = lower.split_at_mut(sk);
                let (uhead, utail) = upper.split_at_mut(sk);
                let rest = a + 1 - sk..ek - sk;
                for (x, &y) in lhead[si..].iter_mut().zip(&ltail[rest.clone()]) {
                    *x -= uik * y;
                }
                for (x, &y) in uhead[si..].iter_mut().zip(&utail[rest]) {
                    *x -= lki * y;
                }
                lower[a] = lki;
                upper[a] = uik;
            }
        }
        Some(TreeLdl {
            inv_diag: diag.iter().map(|d| 1.0 / d).collect(),
            start,
            cols,
            vals: lower,
            upper: Some(upper),
        })
    }

    /// Factors the lower triangle of `m` (symmetric) along `parent`; `None` if `parent` is not a
    /// topological order of `m`'s size or a pivot is not positive and finite.
    pub fn new(m: &DMatrix<Real>, parent: &[usize]) -> Option<TreeLdl> {
        let n = m.nrows();
        // Row `k` of `L` below the diagonal holds `k`'s ancestors, nearest first; the
        // ancestors of an ancestor `i` of `k` are the entries of `k`'s row after `i`, in
        // the same order as in `i`'s own row. The elimination (from the leaves up) then
        // works on these rows only, as MuJoCo's `mj_factorM`.
        let (start, cols, mut vals, _) = Self::gather(m, parent)?;
        let mut diag: Vec<Real> = (0..n).map(|k| m[(k, k)]).collect();
        for k in (0..n).rev() {
            let dk = diag[k];
            if !(dk > 0.0 && dk.is_finite()) {
                return None;
            }
            let (sk, ek) = (start[k], start[k + 1]);
            for a in sk..ek {
                let i = cols[a];
                let lki = vals[a];
                let tmp = lki / dk;
                diag[i] -= tmp * lki;
                // `i`'s row and the rest of `k`'s row list the same ancestors; `i < k`,
                // so `i`'s row lies before `k`'s.
                let si = start[i];
                let (head, tail) = vals.split_at_mut(sk);
                for (x, &y) in head[si..si + (ek - a - 1)].iter_mut().zip(&tail[a + 1 - sk..]) {
                    *x -= tmp * y;
                }
                vals[a] = tmp;
            }
        }
        Some(TreeLdl {
            inv_diag: diag.iter().map(|d| 1.0 / d).collect(),
            start,
            cols,
            vals,
            upper: None,
        })
    }

    /// Solves `M x = b` in place for one column.
    pub fn solve_column<R2: Dim, S2>(&self, x: &mut Matrix<Real, R2, na::U1, S2>)
    where
        S2: StorageMut<Real, R2, na::U1>,
    {
        // The sweeps run on a contiguous copy: indexing a generic (possibly strided)
        // column costs several times the arithmetic of the sweeps themselves.
        const STACK: usize = 64;
        let n = self.inv_diag.len();
        if n <= STACK {
            let mut buf = [0.0; STACK];
            for (k, b) in buf[..n].iter_mut().enumerate() {
                *b = x[k];
            }
            self.solve_slice(&mut buf[..n]);
            for (k, b) in buf[..n].iter().enumerate() {
                x[k] = *b;
            }
        } else {
            let mut buf: Vec<Real> = (0..n).map(|k| x[k]).collect();
            self.solve_slice(&mut buf);
            for (k, b) in buf.iter().enumerate() {
                x[k] = *b;
            }
        }
    }

    /// Solves `M x = b` in place for `x` of the matrix's size.
    pub fn solve_slice(&self, x: &mut [Real]) {
        let n = self.inv_diag.len();
        assert_eq!(x.len(), n, "TreeLdl::solve_slice: wrong length");
        // Lᵀ y = b, from the leaves up (a zero entry adds nothing to its ancestors).
        for k in (0..n).rev() {
            self.up_sweep(x, k);
        }
        self.down_sweep(x);
    }

    /// [`TreeLdl::solve_slice`] for a `b` that is zero outside `chain`: a DoF and all its
    /// ancestors, listed from the DoF to the root (descending indices), as the body
    /// Jacobian of a link is. The sweep from the leaves up then stays on the chain.
    pub fn solve_slice_on_chain(&self, x: &mut [Real], chain: &[usize]) {
        let n = self.inv_diag.len();
        assert_eq!(x.len(), n, "TreeLdl::solve_slice_on_chain: wrong length");
        for &k in chain {
            self.up_sweep(x, k);
        }
        self.down_sweep(x);
    }

    /// [`TreeLdl::solve_slice_on_chain`] for `D` right-hand sides at once, stored by rows
    /// (`x[k]` holds DoF `k` of every column), each zero outside `chain`: one pass over
    /// `L` serves all `D` columns.
    pub fn solve_rows_on_chain<const D: usize>(&self, x: &mut [[Real; D]], chain: &[usize]) {
        let n = self.inv_diag.len();
        assert_eq!(x.len(), n, "TreeLdl::solve_rows_on_chain: wrong length");
        for &k in chain {
            let xk = x[k];
            let (cols, vals) = self.upper_column(k);
            for (&i, &l) in cols.iter().zip(vals) {
                // SAFETY: `i < k < n` (see `up_sweep`).
                let xi = unsafe { x.get_unchecked_mut(i) };
                for (a, b) in xi.iter_mut().zip(&xk) {
                    *a -= l * b;
                }
            }
        }
        for k in 0..n {
            let mut acc = x[k].map(|v| v * self.inv_diag[k]);
            let (cols, vals) = self.row(k);
            for (&i, &l) in cols.iter().zip(vals) {
                // SAFETY: as above.
                let xi = unsafe { x.get_unchecked(i) };
                for (a, b) in acc.iter_mut().zip(xi) {
                    *a -= l * b;
                }
            }
            x[k] = acc;
        }
    }

    /// Subtracts `x[k]` times column `k` of `U` from `k`'s ancestors.
    #[inline(always)]
    fn up_sweep(&self, x: &mut [Real], k: usize) {
        let xk = x[k];
        if xk != 0.0 {
            let (cols, vals) = self.upper_column(k);
            for (&i, &l) in cols.iter().zip(vals) {
                // SAFETY: `i` is an ancestor of `k < n = x.len()`, so `i < k` (checked
                // when the factor was built).
                unsafe { *x.get_unchecked_mut(i) -= l * xk };
            }
        }
    }

    /// `D z = y`, then `L x = z` from the root down.
    #[inline(always)]
    fn down_sweep(&self, x: &mut [Real]) {
        for k in 0..x.len() {
            let (cols, vals) = self.row(k);
            let mut acc = x[k] * self.inv_diag[k];
            for (&i, &l) in cols.iter().zip(vals) {
                // SAFETY: as in `up_sweep`, `i < k < x.len()`.
                acc -= l * unsafe { *x.get_unchecked(i) };
            }
            x[k] = acc;
        }
    }

    /// Row `k` of `L` below the diagonal: its columns and values.
    #[inline(always)]
    fn row(&self, k: usize) -> (&[usize], &[Real]) {
        let r = self.start[k]..self.start[k + 1];
        (&self.cols[r.clone()], &self.vals[r])
    }

    /// Column `k` of `U` above the diagonal: its rows and values (row `k` of `L`
    /// transposed for a symmetric matrix).
    #[inline(always)]
    fn upper_column(&self, k: usize) -> (&[usize], &[Real]) {
        let r = self.start[k]..self.start[k + 1];
        let vals = self.upper.as_deref().unwrap_or(&self.vals);
        (&self.cols[r.clone()], &vals[r])
    }
}

/// `out[a][b] += Σ_rs j[r][a] mid[r][s] j[s][b]` over the columns `cols` only: the
/// quadratic form `jᵀ mid j` of a body Jacobian `j` that is zero outside `cols`. `mid`
/// must be symmetric (a body's mass matrix): each product is computed once for `(a, b)`
/// and `(b, a)`.
pub fn sparse_quadform<C: Dim, S>(
    out: &mut DMatrix<Real>,
    mid: &na::SMatrix<Real, { crate::math::SPATIAL_DIM }, { crate::math::SPATIAL_DIM }>,
    j: &Matrix<Real, na::Const<{ crate::math::SPATIAL_DIM }>, C, S>,
    cols: &[usize],
) where
    S: na::Storage<Real, na::Const<{ crate::math::SPATIAL_DIM }>, C>,
{
    for (ib, &b) in cols.iter().enumerate() {
        let mjb = mid * j.column(b);
        out[(b, b)] += j.column(b).dot(&mjb);
        for &a in &cols[ib + 1..] {
            let v = j.column(a).dot(&mjb);
            out[(a, b)] += v;
            out[(b, a)] += v;
        }
    }
}

/// `out[:, c] += alpha · a · b[:, c]` for each column `c` in `cols`, the other columns
/// left as they are: a small square matrix times a Jacobian-shaped matrix that is zero
/// outside `cols` (the Coriolis terms of a link, over its ancestor chain). Fixed-size, so
/// that each column is a few unrolled operations.
pub fn gemm_cols<const R: usize, SO, SB>(
    out: &mut Matrix<Real, na::Const<R>, Dyn, SO>,
    alpha: Real,
    a: &na::SMatrix<Real, R, R>,
    b: &Matrix<Real, na::Const<R>, Dyn, SB>,
    cols: &[usize],
) where
    SO: StorageMut<Real, na::Const<R>, Dyn>,
    SB: na::Storage<Real, na::Const<R>, Dyn>,
{
    for &c in cols {
        let v: na::SVector<Real, R> = b.fixed_view::<R, 1>(0, c).into_owned();
        let mut o = out.fixed_view_mut::<R, 1>(0, c);
        o += (a * v) * alpha;
    }
}

/// `out[a][b] += Σ_r lhs[r][a] rhs[r][b]` over the columns `cols` only: `lhsᵀ rhs` for
/// two Jacobian-shaped matrices that are zero outside `cols`.
pub fn sparse_gemm_tr<R: Dim, C: Dim, S1, S2>(
    out: &mut DMatrix<Real>,
    lhs: &Matrix<Real, R, C, S1>,
    rhs: &Matrix<Real, R, C, S2>,
    cols: &[usize],
) where
    S1: na::Storage<Real, R, C>,
    S2: na::Storage<Real, R, C>,
{
    for &b in cols {
        let rb = rhs.column(b);
        for &a in cols {
            out[(a, b)] += lhs.column(a).dot(&rb);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gemm_cols_matches_gemm_on_the_listed_columns() {
        let a = na::Matrix3::new(1.0, 2.0, 0.5, -1.0, 0.0, 3.0, 2.0, 1.0, -2.0);
        let b = na::Matrix3xX::<Real>::from_fn(5, |r, c| (r * 5 + c) as Real * 0.1 - 0.4);
        let mut full = na::Matrix3xX::<Real>::from_element(5, 1.0);
        full.gemm(0.5, &a, &b, 1.0);
        let mut part = na::Matrix3xX::<Real>::from_element(5, 1.0);
        gemm_cols(&mut part, 0.5, &a, &b, &[0, 3]);
        for c in 0..5 {
            for r in 0..3 {
                let want = if c == 0 || c == 3 { full[(r, c)] } else { 1.0 };
                assert!((part[(r, c)] - want).abs() < 1e-6, "({r}, {c})");
            }
        }
    }

    /// A tree of 5 DoFs: 0 <- 1 <- 2 and 0 <- 3 <- 4 (two "fingers" on one root DoF).
    fn tree() -> Vec<usize> {
        vec![NO_PARENT, 0, 1, 0, 3]
    }

    /// A random tree-sparse SPD matrix: Σ Jᵢᵀ Jᵢ + I with Jᵢ zero outside DoF i's chain.
    fn tree_spd(parent: &[usize]) -> DMatrix<Real> {
        let n = parent.len();
        let mut m = DMatrix::<Real>::identity(n, n);
        let mut seed = 12345u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as Real / (1u32 << 24) as Real - 0.5
        };
        for k in 0..n {
            let mut chain = vec![];
            let mut i = k;
            while i != NO_PARENT {
                chain.push(i);
                i = parent[i];
            }
            let j: Vec<Real> = (0..n)
                .map(|c| if chain.contains(&c) { rnd() } else { 0.0 })
                .collect();
            for a in 0..n {
                for b in 0..n {
                    m[(a, b)] += j[a] * j[b];
                }
            }
        }
        m
    }

    #[test]
    fn tree_solve_matches_dense_lu() {
        let p = tree();
        let m = tree_spd(&p);
        // Entries between the two branches are zero: the sparsity the factor relies on.
        assert_eq!(m[(2, 4)], 0.0);
        let t = TreeLdl::new(&m, &p).expect("SPD tree matrix");
        let b = na::DVector::<Real>::from_vec(vec![1.0, -2.0, 0.5, 3.0, -1.0]);
        let mut x = b.clone();
        t.solve_column(&mut x);
        let r = &m * &x - &b;
        assert!(r.amax() < 1e-4, "residual {r}");
        let mut y = b.clone();
        LU::new(m.clone()).solve_mut(&mut y);
        assert!((x - y).amax() < 1e-4);
    }

    #[test]
    fn chain_solve_matches_full_solve() {
        let p = tree();
        let m = tree_spd(&p);
        let t = TreeLdl::new(&m, &p).expect("SPD tree matrix");
        // A right-hand side zero outside DoF 4 and its ancestors, listed leaf first.
        let mut chain = vec![4];
        while p[*chain.last().unwrap()] != NO_PARENT {
            chain.push(p[*chain.last().unwrap()]);
        }
        let mut b = vec![0.0; p.len()];
        for (k, &c) in chain.iter().enumerate() {
            b[c] = 1.0 + k as Real;
        }
        let mut full = b.clone();
        t.solve_slice(&mut full);
        let mut on_chain = b.clone();
        t.solve_slice_on_chain(&mut on_chain, &chain);
        assert_eq!(full, on_chain);
        let mut rows: Vec<[Real; 2]> = b.iter().map(|&v| [v, 2.0 * v]).collect();
        t.solve_rows_on_chain(&mut rows, &chain);
        for (r, f) in rows.iter().zip(&full) {
            assert!((r[0] - f).abs() < 1e-6 && (r[1] - 2.0 * f).abs() < 1e-5);
        }
        let r = &m * na::DVector::from_vec(full) - na::DVector::from_vec(b);
        assert!(r.amax() < 1e-4, "residual {r}");
    }

    #[test]
    fn unsymmetric_tree_solve_matches_dense_lu() {
        let p = tree();
        let mut m = tree_spd(&p);
        // A non-symmetric part with the tree's sparsity, as the Coriolis terms add.
        for (k, &i) in p.iter().enumerate() {
            if i != NO_PARENT {
                m[(k, i)] += 0.3 + 0.1 * k as Real;
                m[(i, k)] -= 0.2;
            }
        }
        m[(4, 0)] += 0.25;
        assert_ne!(m[(1, 0)], m[(0, 1)]);
        let t = TreeLdl::new_unsymmetric(&m, &p).expect("tree matrix with positive pivots");
        let b = na::DVector::<Real>::from_vec(vec![1.0, -2.0, 0.5, 3.0, -1.0]);
        let mut x = b.clone();
        t.solve_column(&mut x);
        let r = &m * &x - &b;
        assert!(r.amax() < 1e-4, "residual {r}");
        let mut y = b.clone();
        LU::new(m.clone()).solve_mut(&mut y);
        assert!((&x - &y).amax() < 1e-4);
        // Six right-hand sides by rows, zero outside DoF 2's chain.
        let chain = [2, 1, 0];
        let mut rows = vec![[0.0; 2]; 5];
        for &c in &chain {
            rows[c] = [1.0 + c as Real, -(c as Real)];
        }
        let cols = rows.clone();
        t.solve_rows_on_chain(&mut rows, &chain);
        for k in 0..2 {
            let mut col = na::DVector::<Real>::from_fn(5, |r, _| cols[r][k]);
            LU::new(m.clone()).solve_mut(&mut col);
            for r in 0..5 {
                assert!((rows[r][k] - col[r]).abs() < 1e-4, "({r}, {k})");
            }
        }
        // Symmetric input: the same factor as `new`.
        let sym = tree_spd(&p);
        let (a, b) = (
            TreeLdl::new(&sym, &p).unwrap(),
            TreeLdl::new_unsymmetric(&sym, &p).unwrap(),
        );
        assert_eq!(a.vals, b.vals);
        assert_eq!(a.inv_diag, b.inv_diag);
        // A non-positive pivot falls back to the dense LU.
        let mut bad = m.clone();
        bad[(3, 3)] = 0.0;
        bad[(4, 4)] = 0.0;
        assert!(matches!(
            MassFactor::new_unsymmetric(&bad, 5, Some(&p)),
            MassFactor::Dense(_)
        ));
    }

    #[test]
    fn bad_orders_and_pivots_fall_back_to_dense() {
        let m = tree_spd(&tree());
        // A parent after its child is not a topological order.
        assert!(TreeLdl::new(&m, &[NO_PARENT, 2, 0, 0, 3]).is_none());
        let mut bad = m.clone();
        bad[(4, 4)] = -1.0;
        assert!(TreeLdl::new(&bad, &tree()).is_none());
        assert!(matches!(
            MassFactor::new(&bad, 5, Some(&tree())),
            MassFactor::Dense(_)
        ));
        // A leading block is factored densely.
        assert!(matches!(
            MassFactor::new(&m, 3, Some(&tree())),
            MassFactor::Dense(_)
        ));
    }

    #[test]
    fn sparse_products_match_dense_ones() {
        let n = 5;
        let cols = [3usize, 0];
        let mut j = na::Matrix6xX::<Real>::zeros(n);
        for r in 0..6 {
            j[(r, 0)] = r as Real + 1.0;
            j[(r, 3)] = 0.5 - r as Real;
        }
        let mut mid = na::SMatrix::<Real, 6, 6>::identity() * 2.0;
        mid[(0, 1)] = 0.3;
        mid[(1, 0)] = 0.3;
        let mut dense = DMatrix::<Real>::zeros(n, n);
        dense.quadform(1.0, &mid, &j, 1.0);
        let mut sparse = DMatrix::<Real>::zeros(n, n);
        sparse_quadform(&mut sparse, &mid, &j, &cols);
        assert!((&dense - &sparse).amax() < 1e-5);
        let k = j.map(|v| v * 0.25 + 1.0).component_mul(&j.map(|v| (v != 0.0) as u8 as Real));
        let mut dense = DMatrix::<Real>::zeros(n, n);
        dense.gemm_tr(1.0, &j, &k, 1.0);
        let mut sparse = DMatrix::<Real>::zeros(n, n);
        sparse_gemm_tr(&mut sparse, &j, &k, &cols);
        assert!((&dense - &sparse).amax() < 1e-5);
    }
}
