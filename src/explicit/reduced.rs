//! A gear body's far block — the elements no contact reaches while a window lasts — as a
//! linear elastic substructure in the hub frame, reduced by Craig–Bampton, with the inertia
//! of its rotation kept exact.
//!
//! # The reduction (Craig & Bampton 1968)
//! The block's nodes split into the interface b (nodes it shares with the rest of the mesh),
//! the held nodes (the bore: fixed in the hub frame, the hubs are rigid) and the internal
//! nodes i. Its displacement in the hub frame is
//! ```text
//! u = T z,   T = [ I    0    0  ]   (rows b)        z = [u_b; q; r]
//!                [ Ψ_i  Φ_i  R_i ]   (rows i)
//! Ψ_i = −K_ii⁻¹ K_ib       constraint modes: the static shapes of unit interface motions
//! K_ii Φ_i = M_ii Φ_i Λ    fixed-interface modes, M-orthonormal, the lowest up to a cutoff
//! R_i                      residual vectors: the static shapes K_ii⁻¹ M_ii X_i and
//!                          K_ii⁻¹ M_ii (J X)_i of the centrifugal and the angular-acceleration
//!                          loads, M-orthogonalized against Φ_i and each other
//! ```
//! (J turns a node's vector by +90°: J(a, b) = (−b, a)). The reduced matrices are
//! K_red = Tᵀ K T and M_red = Tᵀ M T, K the block's stiffness and M its lumped masses (the
//! interface nodes' whole masses, their other elements' shares included; none on the held
//! nodes). The contract with the rest of the mesh: it counts neither the interface nodes'
//! masses nor the held nodes' (in its accelerations, kinetic energy and momentum), and the
//! hub's inertia holds the held nodes' whole masses, as the explicit pair's rigid hubs do. A static interface load gives the full
//! model's interface displacements exactly (the constraint modes span every static state
//! without internal loads); with the residual vectors so do the steady centrifugal and
//! angular-acceleration loads on a held interface. The reduced frequencies are Rayleigh–Ritz
//! upper bounds of the full ones (also its highest: the reduced block is stable at any step
//! the full one is).
//!
//! # Motion in the turning hub frame
//! A block node is at x = c + R(θ) y with y = X + u, θ the gear's rotation and ω = θ̇; its
//! velocity is ẋ = R(θ)(ẏ + ω J y). The block's kinetic energy
//! T = ½ Σ m |ẏ + ω J y|² = ½ żᵀ M_red ż + ω s(z)ᵀ ż + ½ ω² I(z), with
//! ```text
//! s(z) = g_X + G z,  G = Tᵀ M J T (skew),  g_X = Tᵀ M J X,
//! I(z) = I_X + 2 m_Xᵀ z + zᵀ M_red z,       m_X = Tᵀ M X,  I_X = Σ m |X|²,
//! ```
//! gives by Lagrange's equations (the rotating-frame form of Shabana's floating frame of
//! reference, *Dynamics of Multibody Systems*, ch. 5, for a plane body)
//! ```text
//! M_red z̈ + ω̇ s(z) = Q_z − K_red z − β K_red ż − 2ω G ż + ω² (m_X + M_red z)
//! I(z) ω̇ + s(z)ᵀ z̈ + 2ω (m_X + M_red z)ᵀ ż = τ_b + τ_hub
//! ```
//! Q_z holds the forces F_b = R(θ)ᵀ f_b the rest of the mesh puts on the interface nodes (hub
//! frame) in its first 2·|b| entries, τ_b = Σ_b y_b × F_b is their moment about the centre, τ_hub
//! the hub's torque on the block, and β K_red ż the stiffness-proportional damping of the
//! explicit bodies on the velocity relative to the hub frame (the corotational elements take
//! theirs relative to the element's translation, whose spin K removes to first order: they
//! differ by β ω K J u, about 4e-7 of the elastic force at 3000 rpm). With the hub turned at a prescribed rate the first equation
//! gives z̈ and the second the torque the hub must apply; with a free hub of inertia I_h under
//! a torque τ the two are solved together with I_h ω̇ = τ − τ_hub. The energy account:
//! T above, V = ½ zᵀ K_red z, damping power β żᵀ K_red ż; the angular momentum about the
//! centre is s(z)ᵀ ż + ω I(z).
//!
//! # The step
//! The state lives in the reduced block's own modes z = V η (K_red V = M_red V Ω²,
//! Vᵀ M_red V = I), where M_red and K_red are diagonal: a step takes u_b = V_b η and
//! u̇_b = V_b η̇ (to place the interface nodes), V_bᵀ F_b and Ĝ (η̇, η) with Ĝ = Vᵀ G V, and
//! O(n) work besides; no solve. Ĝ is skew (G is), so the step holds its upper triangle only
//! ([`SkewMatrix`]) and reads each entry once for both products and both triangles.
//!
//! Ĝ couples every pair of own modes, a dense n × n product, yet its term 2ω Ĝ η̇ is small
//! beside the modes' elastic forces Ω_j² η_j wherever Ω_j ≫ ω. With Ĝ's entries bounded
//! (|Ĝ_jk| ≤ 1: V is M_red-orthonormal and J keeps each node's mass-weighted length), a
//! coupling between modes j and k with Ω_j ≥ 2ω/ε moves mode j, driven at mode k's frequency
//! Ω_k ≤ Ω_j, by |η_j| ≤ 2ω Ω_k |η_k| / Ω_j² ≤ ε |η_k|, and puts on mode k at most ε times
//! mode j's elastic force (and the Euler term ω̇ Ĝ η moves mode j by ω̇/Ω_j² of |η_k|,
//! 1e-7 at the 3000 rpm scene's driven-hub accelerations). Two modes left out with near-equal
//! frequencies (the teeth's clusters) are not moved quasi-statically but split: their
//! frequencies by at most ω |Ĝ_jk| ≤ ε Ω_j / 2. So the block keeps Ĝ among its
//! own modes below 2 ω_max / ε only ([`CORIOLIS_TOLERANCE`] ε = 1e-3, ω_max the largest |ω|
//! the hub may reach, which the explicit pair sets and checks), the same Ĝ in the energy
//! and the momentum, so that the model keeps its own energy exactly: at 3000 rpm (ω_max
//! twice the speed: the own modes below 200 kHz) 180 of the paper driver block's 294 at a
//! cutoff of 214 kHz, a third of Ĝ's products (validation/performance).
//!
//! # Where the modes kept stop
//! The explicit pair cuts a block off at a multiple of the lowest mode of the fine sectors
//! beside it, held where they meet the block and at the bore ([`Cutoff::BesideBlockTimes`],
//! [`lowest_mode_beside_block`]): those sectors carry the contact and load the block at their
//! own frequencies and above, so the block's modes are kept to several times theirs, and the
//! modes above respond quasi-statically (their static part is in the constraint modes). A
//! multiple of the block's own lowest mode, the rule before, stopped too low on a large gear
//! (a large rim has a low lowest mode) and too high on a small one (validation/performance,
//! lever 2f).
//!
//! On the 3000 rpm scene's window mesh of the paper's driver
//! (six fine teeth) the block is 1 440 of the 2 046 elements and 4 716 nodes, its interface
//! the two radial edges beside the fine sectors (48 nodes), and an 80 kHz cutoff keeps 45
//! modes: 143 reduced DOFs, built in about 2 s. Checked against the full block and the full
//! explicit body in the tests below; in the explicit pair's step through
//! [`crate::explicit::far`] (`fe.far_body = "reduced"`).

use nalgebra::{Cholesky, DMatrix, DVector, Point2};

use crate::fe::assembly::{stiffness_triplets, symmetric_product, FactorizedStiffness, FeError};
use crate::fe::modal::{lane_dot as dot, lowest_modes_within};
use crate::fe::q8::elasticity_matrix;

use super::body::ExplicitMaterial;
use super::body::Kernel;

/// The relative Lanczos residual of the fixed-interface modes below the cutoff: they span the
/// block's basis, and a Ritz vector of residual r leaves the exact modes' span by about r over
/// the relative gap (its frequency by r²), far below the truncation at the cutoff. On the
/// paper's gears at 16 times the block's lowest mode (about 340 modes sought for 200 kept)
/// 1e-9 for all of them took 1 400 Krylov vectors and 47 s a block, 700 and 12 s with this;
/// now only the modes below the cutoff and the first above it are sought
/// ([`lowest_modes_within`]).
pub const FIXED_INTERFACE_MODE_TOLERANCE: f64 = 1e-4;

/// ε of the Coriolis couplings a block keeps (module doc): each left out moves what it
/// couples by less than this fraction.
pub const CORIOLIS_TOLERANCE: f64 = 1e-3;

/// The step's products compiled for the widest vector unit the CPU has ([`Kernel::best`]), the
/// same bits on every one (no sum is reordered, no multiply and add fused): the bodies are
/// `#[inline(always)]` and so built again inside each `#[target_feature]` function.
mod widest {
    use super::{DMatrix, Kernel, SkewMatrix};

    type Pair<'a> = (&'a [f64], &'a [f64]);
    type PairMut<'a> = (&'a mut [f64], &'a mut [f64]);
    type TripleMut<'a> = (&'a mut [f64], &'a mut [f64], &'a mut [f64]);

    pub(super) fn product_twice(matrix: &DMatrix<f64>, x: Pair, y: PairMut) {
        match Kernel::best() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `best` returns a kernel this CPU runs.
            Kernel::Avx512 => unsafe { x86::product_twice_avx512(matrix, x, y) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Kernel::Avx2 => unsafe { x86::product_twice_avx2(matrix, x, y) },
            _ => super::product_twice(matrix, x, y),
        }
    }

    pub(super) fn skew_product_twice(matrix: &SkewMatrix, x: Pair, y: PairMut) {
        match Kernel::best() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `best` returns a kernel this CPU runs.
            Kernel::Avx512 => unsafe { x86::skew_product_twice_avx512(matrix, x, y) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Kernel::Avx2 => unsafe { x86::skew_product_twice_avx2(matrix, x, y) },
            _ => super::skew_product_twice(matrix, x, y),
        }
    }

    pub(super) fn modal_products(
        interface_modes: &DMatrix<f64>,
        interface_force: &[f64],
        gyroscopic: &SkewMatrix,
        rates: Pair,
        out: TripleMut,
    ) {
        let args = (interface_modes, interface_force, gyroscopic);
        match Kernel::best() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `best` returns a kernel this CPU runs.
            Kernel::Avx512 => unsafe { x86::modal_products_avx512(args, rates, out) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Kernel::Avx2 => unsafe { x86::modal_products_avx2(args, rates, out) },
            _ => super::modal_products(args.0, args.1, args.2, rates, out),
        }
    }

    #[cfg(target_arch = "x86_64")]
    mod x86 {
        use super::{DMatrix, Pair, PairMut, SkewMatrix, TripleMut};
        type Args<'a> = (&'a DMatrix<f64>, &'a [f64], &'a SkewMatrix);

        #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
        pub(super) unsafe fn product_twice_avx512(m: &DMatrix<f64>, x: Pair, y: PairMut) {
            super::super::product_twice(m, x, y)
        }

        #[target_feature(enable = "avx2,fma")]
        pub(super) unsafe fn product_twice_avx2(m: &DMatrix<f64>, x: Pair, y: PairMut) {
            super::super::product_twice(m, x, y)
        }

        #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
        pub(super) unsafe fn skew_product_twice_avx512(m: &SkewMatrix, x: Pair, y: PairMut) {
            super::super::skew_product_twice(m, x, y)
        }

        #[target_feature(enable = "avx2,fma")]
        pub(super) unsafe fn skew_product_twice_avx2(m: &SkewMatrix, x: Pair, y: PairMut) {
            super::super::skew_product_twice(m, x, y)
        }

        #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
        pub(super) unsafe fn modal_products_avx512(a: Args, rates: Pair, out: TripleMut) {
            super::super::modal_products(a.0, a.1, a.2, rates, out)
        }

        #[target_feature(enable = "avx2,fma")]
        pub(super) unsafe fn modal_products_avx2(a: Args, rates: Pair, out: TripleMut) {
            super::super::modal_products(a.0, a.1, a.2, rates, out)
        }
    }
}

/// (y1, y2) = A (x1, x2) for a column-major A: rows in blocks of [`ROWS`] whose sums stay in
/// registers across the columns (a column at a time, each y_i summed over j in order, so
/// every vector unit gives the same bits).
#[inline(always)]
fn product_twice(
    matrix: &DMatrix<f64>,
    (x1, x2): (&[f64], &[f64]),
    (y1, y2): (&mut [f64], &mut [f64]),
) {
    let rows = matrix.nrows();
    assert!(
        y1.len() == rows && y2.len() == rows && x1.len() == matrix.ncols() && x2.len() == x1.len()
    );
    let data = matrix.as_slice();
    let mut start = 0;
    while start + ROWS <= rows {
        let (mut s1, mut s2) = ([0.0; ROWS], [0.0; ROWS]);
        for (j, (&a1, &a2)) in x1.iter().zip(x2).enumerate() {
            let column: &[f64; ROWS] = data[j * rows + start..j * rows + start + ROWS]
                .try_into()
                .expect("a block of rows");
            for k in 0..ROWS {
                s1[k] += column[k] * a1;
                s2[k] += column[k] * a2;
            }
        }
        y1[start..start + ROWS].copy_from_slice(&s1);
        y2[start..start + ROWS].copy_from_slice(&s2);
        start += ROWS;
    }
    let rest = rows - start;
    if rest > 0 {
        let (mut s1, mut s2) = ([0.0; ROWS], [0.0; ROWS]);
        for (j, (&a1, &a2)) in x1.iter().zip(x2).enumerate() {
            let column = &data[j * rows + start..j * rows + rows];
            for k in 0..rest {
                s1[k] += column[k] * a1;
                s2[k] += column[k] * a2;
            }
        }
        y1[start..].copy_from_slice(&s1[..rest]);
        y2[start..].copy_from_slice(&s2[..rest]);
    }
}

/// Rows a block of [`product_twice`] sums in registers (two of AVX-512's eight lanes each for
/// y1 and y2).
const ROWS: usize = 16;

/// A step's two products: V_bᵀ F_b into `force` (a dot product per column of V_b) and
/// (Ĝ η̇, Ĝ η) into (`g_rate`, `g_eta`).
#[inline(always)]
fn modal_products(
    interface_modes: &DMatrix<f64>,
    interface_force: &[f64],
    gyroscopic: &SkewMatrix,
    rates: (&[f64], &[f64]),
    (force, g_rate, g_eta): (&mut [f64], &mut [f64], &mut [f64]),
) {
    let nb = interface_modes.nrows();
    for (f, column) in force
        .iter_mut()
        .zip(interface_modes.as_slice().chunks_exact(nb))
    {
        *f = dot(column, interface_force);
    }
    skew_product_twice(gyroscopic, rates, (g_rate, g_eta));
}

/// A skew-symmetric matrix (Aᵀ = −A, zero diagonal) held by its strict upper triangle, column
/// after column (column j: A₀ⱼ … A_{j−1,j}): half the entries of the dense matrix, so that a
/// step's products with Ĝ read half the memory (at the FE sweep's speeds Ĝ couples all of a
/// block's modes, about 290 × 290 on the paper's gears, and the two blocks' Ĝ no longer fit
/// a core's cache beside the rest of the step).
#[derive(Debug, Clone, PartialEq)]
pub struct SkewMatrix {
    dim: usize,
    upper: Vec<f64>,
}

impl SkewMatrix {
    /// The skew part ½(A − Aᵀ) of the square matrix `a`.
    pub fn skew_part_of(a: &DMatrix<f64>) -> Self {
        assert!(a.is_square(), "a square matrix");
        let dim = a.nrows();
        let mut upper = Vec::with_capacity(dim * dim.saturating_sub(1) / 2);
        for j in 0..dim {
            for i in 0..j {
                upper.push(0.5 * (a[(i, j)] - a[(j, i)]));
            }
        }
        SkewMatrix { dim, upper }
    }

    /// The number of rows (and columns).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Column j above the diagonal: A₀ⱼ … A_{j−1,j}.
    #[inline(always)]
    fn column(&self, j: usize) -> &[f64] {
        let start = j * j.saturating_sub(1) / 2;
        &self.upper[start..start + j]
    }

    /// Every entry times `factor`.
    pub fn scale(&mut self, factor: f64) {
        self.upper.iter_mut().for_each(|a| *a *= factor);
    }

    /// The dense matrix.
    pub fn to_dense(&self) -> DMatrix<f64> {
        DMatrix::from_fn(self.dim, self.dim, |i, j| match i.cmp(&j) {
            std::cmp::Ordering::Less => self.column(j)[i],
            std::cmp::Ordering::Greater => -self.column(i)[j],
            std::cmp::Ordering::Equal => 0.0,
        })
    }

    /// A x, by the step's product ([`skew_product_twice`]).
    pub fn times(&self, x: &[f64]) -> Vec<f64> {
        let (mut y, mut unused) = (vec![0.0; self.dim], vec![0.0; self.dim]);
        widest::skew_product_twice(self, (x, x), (&mut y, &mut unused));
        y
    }
}

/// (y1, y2) = A (x1, x2) for a skew-symmetric A held by its upper triangle: column j adds
/// A_ij x_j to the rows i < j above it and gives row j its part below the diagonal,
/// y_j = −Σ_{i<j} A_ij x_i (in [`LANES`] sums, row i in lane i mod [`LANES`]), before any later
/// column adds to it; each matrix entry is read once for four products. The columns go in
/// groups of [`GROUP`] that share each load and store of x and y; every y_i is summed in the
/// same order whatever the grouping and on every vector unit.
#[inline(always)]
fn skew_product_twice(
    matrix: &SkewMatrix,
    x: (&[f64], &[f64]),
    (y1, y2): (&mut [f64], &mut [f64]),
) {
    let n = matrix.dim;
    assert!(x.0.len() == n && x.1.len() == n && y1.len() == n && y2.len() == n);
    let mut first = 0;
    while first + GROUP <= n {
        skew_columns::<GROUP>(matrix, first, x, (y1, y2));
        first += GROUP;
    }
    for j in first..n {
        skew_columns::<1>(matrix, j, x, (y1, y2));
    }
}

/// Columns `first` .. `first` + G of [`skew_product_twice`].
#[inline(always)]
fn skew_columns<const G: usize>(
    matrix: &SkewMatrix,
    first: usize,
    (x1, x2): (&[f64], &[f64]),
    (y1, y2): (&mut [f64], &mut [f64]),
) {
    let columns: [&[f64]; G] = std::array::from_fn(|k| matrix.column(first + k));
    let a1: [f64; G] = std::array::from_fn(|k| x1[first + k]);
    let a2: [f64; G] = std::array::from_fn(|k| x2[first + k]);
    let (mut d1, mut d2) = ([[0.0; LANES]; G], [[0.0; LANES]; G]);
    // The rows above the group, which every column of it has: whole lanes, then the rest.
    let whole = first / LANES * LANES;
    for start in (0..whole).step_by(LANES) {
        let lanes = |v: &[f64]| -> [f64; LANES] {
            v[start..start + LANES].try_into().expect("a lane's width")
        };
        let (u1, u2) = (lanes(x1), lanes(x2));
        let (mut v1, mut v2) = (lanes(y1), lanes(y2));
        for k in 0..G {
            let c = lanes(columns[k]);
            for l in 0..LANES {
                d1[k][l] += c[l] * u1[l];
                d2[k][l] += c[l] * u2[l];
                v1[l] += c[l] * a1[k];
                v2[l] += c[l] * a2[k];
            }
        }
        y1[start..start + LANES].copy_from_slice(&v1);
        y2[start..start + LANES].copy_from_slice(&v2);
    }
    for i in whole..first {
        let l = i % LANES;
        for k in 0..G {
            let c = columns[k][i];
            d1[k][l] += c * x1[i];
            d2[k][l] += c * x2[i];
            y1[i] += c * a1[k];
            y2[i] += c * a2[k];
        }
    }
    // The group's own triangle: each row set by its own column before the later ones add.
    for k in 0..G {
        let j = first + k;
        for i in first..j {
            let (c, l) = (columns[k][i], i % LANES);
            d1[k][l] += c * x1[i];
            d2[k][l] += c * x2[i];
            y1[i] += c * a1[k];
            y2[i] += c * a2[k];
        }
        y1[j] = -d1[k].iter().sum::<f64>();
        y2[j] = -d2[k].iter().sum::<f64>();
    }
}

/// Columns [`skew_product_twice`] takes at once (with their sums, 24 of AVX-512's 32
/// registers).
const GROUP: usize = 4;

/// The sums a column of [`skew_product_twice`] keeps for its row below the diagonal (one
/// AVX-512 register each).
const LANES: usize = 8;

/// The elements `in_block` and the others, each in the mesh's order.
pub fn split_elements(
    elements: &[[usize; 8]],
    in_block: &[bool],
) -> (Vec<[usize; 8]>, Vec<[usize; 8]>) {
    assert_eq!(in_block.len(), elements.len(), "one flag per element");
    let (block, rest): (Vec<_>, Vec<_>) = elements.iter().zip(in_block).partition(|(_, &b)| b);
    let strip = |v: Vec<(&[usize; 8], &bool)>| v.into_iter().map(|(e, _)| *e).collect();
    (strip(block), strip(rest))
}

type Triplets = Vec<(usize, usize, f64)>;

/// The problem on the DOFs of the nodes `free` (ascending) of a mesh of `nodes` nodes: their
/// numbering (x and y of each in turn; `usize::MAX` for every other DOF), `stiffness`'s entries
/// among them renumbered (ascending on both sides, so the lower triangle stays the lower
/// triangle) and their lumped masses `mass` (one per mesh node) as triplets.
fn on_free_nodes(
    nodes: usize,
    free: &[usize],
    stiffness: &[(usize, usize, f64)],
    mass: &[f64],
) -> (Vec<usize>, Triplets, Triplets) {
    let mut index = vec![usize::MAX; 2 * nodes];
    for (k, &node) in free.iter().enumerate() {
        index[2 * node] = 2 * k;
        index[2 * node + 1] = 2 * k + 1;
    }
    let free_stiffness = stiffness
        .iter()
        .filter_map(|&(r, c, v)| {
            let (fr, fc) = (index[r], index[c]);
            (fr != usize::MAX && fc != usize::MAX).then_some((fr, fc, v))
        })
        .collect();
    let free_mass = (0..2 * free.len())
        .map(|k| (k, k, mass[free[k / 2]]))
        .collect();
    (index, free_stiffness, free_mass)
}

/// The lowest mode [Hz] of the mesh's elements outside the block (`in_block` false: a window's
/// fine sectors) held where they meet the block and at the nodes `held` (the bore): the
/// fundamental of the sectors that carry the contact, as the block sees them (a sector's, not
/// one tooth's: on the paper's driver 61.7 kHz with three fine teeth, 44.6 kHz with six).
pub fn lowest_mode_beside_block(
    nodes: &[Point2<f64>],
    elements: &[[usize; 8]],
    in_block: &[bool],
    held: &[usize],
    mass: &[f64],
    material: &ExplicitMaterial,
) -> Result<f64, FeError> {
    let outside: Vec<bool> = in_block.iter().map(|b| !b).collect();
    let BlockNodes { internal, .. } = BlockNodes::of(nodes.len(), elements, &outside, held);
    let (_, rest) = split_elements(elements, in_block);
    let d = elasticity_matrix(
        material.youngs_modulus,
        material.poisson_ratio,
        material.plane,
    );
    let stiffness = stiffness_triplets(nodes, &rest, &d, material.thickness);
    let (_, stiffness, mass) = on_free_nodes(nodes.len(), &internal, &stiffness, mass);
    let free = 2 * internal.len();
    if free == 0 {
        return Err(FeError::Remeshing(
            "the far block leaves the fine sectors no node of their own: its cutoff has no \
             teeth to follow (fe.far_body = \"full\")"
                .into(),
        ));
    }
    let modes = crate::fe::modal::lowest_modes(free, &stiffness, &mass, 1, 0.0)?;
    Ok(modes[0].frequency_hz)
}

/// A block's nodes in a mesh, each list ascending.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BlockNodes {
    /// Nodes of the block's elements among the mesh's held nodes (the bore).
    pub held: Vec<usize>,
    /// The other nodes the block shares with the rest of the mesh.
    pub interface: Vec<usize>,
    /// The nodes of the block's elements only.
    pub internal: Vec<usize>,
}

impl BlockNodes {
    /// The nodes of the elements `in_block` of a mesh of `nodes` nodes whose nodes `held` ride
    /// on the hub.
    pub fn of(nodes: usize, elements: &[[usize; 8]], in_block: &[bool], held: &[usize]) -> Self {
        let mut block_node = vec![false; nodes];
        let mut outside_node = vec![false; nodes];
        for (e, &b) in elements.iter().zip(in_block) {
            let mark = if b {
                &mut block_node
            } else {
                &mut outside_node
            };
            e.iter().for_each(|&i| mark[i] = true);
        }
        let mut is_held = vec![false; nodes];
        held.iter().for_each(|&i| is_held[i] = true);
        let pick = |keep: &dyn Fn(usize) -> bool| (0..nodes).filter(|&i| keep(i)).collect();
        BlockNodes {
            held: pick(&|i| block_node[i] && is_held[i]),
            interface: pick(&|i| block_node[i] && outside_node[i] && !is_held[i]),
            internal: pick(&|i| block_node[i] && !outside_node[i] && !is_held[i]),
        }
    }
}

/// A block of a gear body reduced to its interface DOFs, fixed-interface modes and residual
/// vectors, with the reduced matrices of its motion in the hub frame.
#[derive(Debug, Clone)]
pub struct ReducedBlock {
    /// Mesh nodes of the interface, in the order of z's first 2·len entries (x, y each).
    pub interface: Vec<usize>,
    /// The block's internal mesh nodes (their DOFs are T's rows i, x and y each).
    pub internal: Vec<usize>,
    /// The block's held nodes (the bore): no displacement in the hub frame.
    pub held: Vec<usize>,
    /// Frequencies of the fixed-interface modes kept [Hz].
    pub mode_frequencies_hz: Vec<f64>,
    /// T's internal rows: 2·internal.len() × dofs().
    pub basis_internal: DMatrix<f64>,
    /// Reference positions X of the interface and internal nodes in the hub frame [m].
    interface_reference: Vec<Point2<f64>>,
    internal_reference: Vec<Point2<f64>>,
    /// Masses of the internal nodes [kg].
    internal_mass: Vec<f64>,
    /// K_red [N/m].
    pub stiffness: DMatrix<f64>,
    /// M_red [kg].
    pub mass: DMatrix<f64>,
    /// The reduced block's own modes V (M_red-orthonormal, z = V η) and their ω² (Ω²).
    modes: DMatrix<f64>,
    modal_squared: Vec<f64>,
    /// V's interface rows V_b (u_b = V_b η), column-major.
    interface_modes: DMatrix<f64>,
    /// Ĝ = Vᵀ G V among the own modes whose Coriolis couplings are kept (the lowest ones,
    /// module doc), m̂ = Vᵀ m_X, ĝ = Vᵀ g_X.
    modal_gyroscopic: SkewMatrix,
    /// The largest |ω| [rad/s] the couplings kept hold for: ε/2 times the first own mode left
    /// out (infinite if none is), at or above the bound [`Self::new`] was asked for.
    rate_bound: f64,
    modal_radial: DVector<f64>,
    modal_turning: DVector<f64>,
    /// G = Tᵀ M J T [kg].
    pub gyroscopic: DMatrix<f64>,
    /// g_X = Tᵀ M J X and m_X = Tᵀ M X [kg·m].
    pub turning_reference: DVector<f64>,
    pub radial_reference: DVector<f64>,
    /// I_X = Σ m |X|² over the interface and internal nodes [kg·m²].
    pub reference_inertia: f64,
}

/// The block's state in the reduced block's own modal coordinates η (z = V η): η, η̇, η̈.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BlockState {
    pub eta: Vec<f64>,
    pub rate: Vec<f64>,
    pub accel: Vec<f64>,
}

impl BlockState {
    /// The drift of a central-difference step: η̇ += ½Δt η̈, η += Δt η̇.
    pub fn drift(&mut self, dt: f64) {
        for ((e, r), a) in self
            .eta
            .iter_mut()
            .zip(self.rate.iter_mut())
            .zip(&self.accel)
        {
            *r += 0.5 * dt * a;
            *e += dt * *r;
        }
    }

    /// The closing kick η̇ += `half` η̈ (`half` = ½Δt).
    pub fn kick(&mut self, half: f64) {
        for (r, a) in self.rate.iter_mut().zip(&self.accel) {
            *r += half * a;
        }
    }
}

/// Work space of [`ReducedBlock`]'s step ([`ReducedBlock::scratch`]).
#[derive(Debug, Clone)]
pub struct BlockScratch {
    /// Ĝ η̇, Ĝ η, V_bᵀ F_b.
    g_rate: Vec<f64>,
    g_eta: Vec<f64>,
    force: Vec<f64>,
    /// u_b and u̇_b of the last [`ReducedBlock::interface_motion`].
    displacement: Vec<f64>,
    displacement_rate: Vec<f64>,
}

impl BlockScratch {
    /// u_b of the last [`ReducedBlock::interface_motion`] (hub frame, x and y per node) [m].
    pub fn interface_displacement(&self) -> &[f64] {
        &self.displacement
    }

    /// u̇_b of the last [`ReducedBlock::interface_motion`] [m/s].
    pub fn interface_rate(&self) -> &[f64] {
        &self.displacement_rate
    }
}

/// What [`ReducedBlock::prepare`] leaves for the hub's equation: I(η), s·y, s·s,
/// (m̂ + η)·η̇ and the interface forces' moment τ_b.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BlockSums([f64; 5]);

/// Where the fixed-interface modes kept stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cutoff {
    /// At a frequency [Hz].
    Hz(f64),
    /// At this many times the lowest mode of the rest of the mesh (the window's fine sectors,
    /// which carry the contact) held at the block and the bore
    /// ([`lowest_mode_beside_block`]): the block keeps its modes to where the teeth beside
    /// it vibrate and well above (module doc, "Where the modes kept stop").
    BesideBlockTimes(f64),
}

/// The hub frame's motion: rate ω [rad/s] and angular acceleration ω̇ [rad/s²].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameMotion {
    pub rate: f64,
    pub accel: f64,
}

impl ReducedBlock {
    /// Reduces the elements `in_block` of the mesh (`nodes` in the hub frame, centre at the
    /// origin; `elements`), whose nodes in `held` ride on the hub, with the nodal masses `mass`
    /// (one per node, of the whole mesh), keeping the fixed-interface modes up to `cutoff` and
    /// the Coriolis couplings of the own modes below 2 `rate_bound` / [`CORIOLIS_TOLERANCE`]
    /// (`rate_bound` the largest |ω| the hub may reach [rad/s]; infinite keeps them all).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        nodes: &[Point2<f64>],
        elements: &[[usize; 8]],
        in_block: &[bool],
        held: &[usize],
        mass: &[f64],
        material: &ExplicitMaterial,
        cutoff: Cutoff,
        rate_bound: f64,
    ) -> Result<Self, FeError> {
        assert_eq!(in_block.len(), elements.len(), "one flag per element");
        assert_eq!(mass.len(), nodes.len(), "one mass per node");
        assert!(
            in_block.iter().any(|b| *b) && in_block.iter().any(|b| !*b),
            "a block and a rest of the mesh"
        );
        let n = nodes.len();
        let target = match cutoff {
            Cutoff::Hz(hz) => (std::f64::consts::TAU * hz).powi(2),
            Cutoff::BesideBlockTimes(k) => {
                let beside =
                    lowest_mode_beside_block(nodes, elements, in_block, held, mass, material)?;
                (std::f64::consts::TAU * k * beside).powi(2)
            }
        };
        let BlockNodes {
            held,
            interface,
            internal,
        } = BlockNodes::of(n, elements, in_block, held);
        let (block_elements, _) = split_elements(elements, in_block);
        let d = elasticity_matrix(
            material.youngs_modulus,
            material.poisson_ratio,
            material.plane,
        );
        let stiffness = stiffness_triplets(nodes, &block_elements, &d, material.thickness);

        // The fixed-interface problem on the internal DOFs, numbered 0..ni.
        let (nb, ni) = (2 * interface.len(), 2 * internal.len());
        let (internal_index, internal_stiffness, mass_triplets) =
            on_free_nodes(n, &internal, &stiffness, mass);
        let fixed: Vec<usize> = (0..2 * n)
            .filter(|&dof| internal_index[dof] == usize::MAX)
            .collect();
        let factor = FactorizedStiffness::new(2 * n, stiffness.clone(), &fixed)?;
        let internal_mass: Vec<f64> = internal.iter().map(|&i| mass[i]).collect();
        // Every mode up to the target and the first above it, converged.
        let modes = lowest_modes_within(
            ni,
            &internal_stiffness,
            &mass_triplets,
            16.min(ni),
            0.0,
            (FIXED_INTERFACE_MODE_TOLERANCE, target),
        )?;
        let modes: Vec<_> = modes
            .into_iter()
            .filter(|m| m.eigenvalue <= target)
            .collect();

        // Constraint modes and the residual vectors' static shapes, in one set of solves.
        let mut loads: Vec<Vec<f64>> = (0..nb)
            .map(|j| {
                let mut unit = vec![0.0; 2 * n];
                unit[2 * interface[j / 2] + j % 2] = 1.0;
                symmetric_product(&stiffness, &unit)
                    .into_iter()
                    .map(|l| -l)
                    .collect()
            })
            .collect();
        for turned in [false, true] {
            let mut load = vec![0.0; 2 * n];
            for &i in &internal {
                let p = nodes[i];
                let (a, b) = if turned { (-p.y, p.x) } else { (p.x, p.y) };
                load[2 * i] = mass[i] * a;
                load[2 * i + 1] = mass[i] * b;
            }
            loads.push(load);
        }
        let solved = factor.solve_columns(&loads);
        let on_internal = |u: &[f64]| -> DVector<f64> {
            DVector::from_iterator(ni, internal.iter().flat_map(|&i| [u[2 * i], u[2 * i + 1]]))
        };
        let m_dot = |a: &DVector<f64>, b: &DVector<f64>| -> f64 {
            (0..ni).map(|k| internal_mass[k / 2] * a[k] * b[k]).sum()
        };
        let mut columns: Vec<DVector<f64>> = solved[..nb].iter().map(|u| on_internal(u)).collect();
        let mut kept: Vec<DVector<f64>> = modes
            .iter()
            .map(|m| DVector::from_column_slice(&m.shape))
            .collect();
        columns.extend(kept.iter().cloned());
        for u in &solved[nb..] {
            let mut r = on_internal(u);
            // Twice against Φ and the residual vectors before it ("twice is enough").
            for _pass in 0..2 {
                for k in &kept {
                    let c = m_dot(k, &r);
                    r.axpy(-c, k, 1.0);
                }
            }
            let norm = m_dot(&r, &r).sqrt();
            // A load the modes already hold (a block too small to bend under it): no vector.
            if norm > 1e-8 * m_dot(&on_internal(u), &on_internal(u)).sqrt() {
                r /= norm;
                kept.push(r.clone());
                columns.push(r);
            }
        }
        let dofs = columns.len();
        let basis_internal = DMatrix::from_columns(&columns);

        // T on the block's interface and internal DOFs (x and y of each node, the interface
        // nodes first): the identity on the interface, the internal rows below.
        let interface_mass: Vec<f64> = interface.iter().map(|&i| mass[i]).collect();
        let interface_reference: Vec<Point2<f64>> = interface.iter().map(|&i| nodes[i]).collect();
        let internal_reference: Vec<Point2<f64>> = internal.iter().map(|&i| nodes[i]).collect();
        let block_dofs: Vec<usize> = interface
            .iter()
            .chain(&internal)
            .flat_map(|&i| [2 * i, 2 * i + 1])
            .collect();
        let rows = block_dofs.len();
        let mut t = DMatrix::zeros(rows, dofs);
        for j in 0..nb {
            t[(j, j)] = 1.0;
        }
        t.rows_mut(nb, ni).copy_from(&basis_internal);
        // K T column by column on the mesh's DOFs, gathered onto the block's: Tᵀ K T.
        let mut k_t = DMatrix::zeros(rows, dofs);
        let mut column = vec![0.0; 2 * n];
        for j in 0..dofs {
            for (r, &d) in block_dofs.iter().enumerate() {
                column[d] = t[(r, j)];
            }
            let product = symmetric_product(&stiffness, &column);
            for (r, &d) in block_dofs.iter().enumerate() {
                k_t[(r, j)] = product[d];
            }
        }
        let mut reduced_stiffness = t.transpose() * &k_t;
        // Exactly symmetric (the two triangles differ by round-off).
        reduced_stiffness = (&reduced_stiffness + reduced_stiffness.transpose()) * 0.5;

        // Mass-weighted sums over the block's nodes: M T, M J T (J turns each node's vector by
        // +90°), M X and M J X.
        let weight = |r: usize| {
            let node = r / 2;
            if node < interface.len() {
                interface_mass[node]
            } else {
                internal_mass[node - interface.len()]
            }
        };
        let reference = |r: usize| {
            let node = r / 2;
            if node < interface.len() {
                interface_reference[node]
            } else {
                internal_reference[node - interface.len()]
            }
        };
        let m_t = DMatrix::from_fn(rows, dofs, |r, j| weight(r) * t[(r, j)]);
        let m_j_t = DMatrix::from_fn(rows, dofs, |r, j| {
            weight(r)
                * if r % 2 == 0 {
                    -t[(r + 1, j)]
                } else {
                    t[(r - 1, j)]
                }
        });
        let m_x = DVector::from_fn(rows, |r, _| weight(r) * reference(r)[r % 2]);
        let m_j_x = DVector::from_fn(rows, |r, _| {
            let p = reference(r);
            weight(r) * if r % 2 == 0 { -p.y } else { p.x }
        });
        let mut reduced_mass = t.transpose() * &m_t;
        let mut gyroscopic = t.transpose() * &m_j_t;
        reduced_mass = (&reduced_mass + reduced_mass.transpose()) * 0.5;
        gyroscopic = (&gyroscopic - gyroscopic.transpose()) * 0.5;
        let turning_reference = t.transpose() * &m_j_x;
        let radial_reference = t.transpose() * &m_x;
        let reference_inertia = (0..rows)
            .step_by(2)
            .map(|r| weight(r) * reference(r).coords.norm_squared())
            .sum();
        let mass_factor =
            Cholesky::new(reduced_mass.clone()).ok_or_else(|| FeError::NotPositiveDefinite {
                reason: "the reduced block's mass matrix".into(),
            })?;
        // K_red v = λ M_red v through L⁻¹ K_red L⁻ᵀ (M_red = L Lᵀ): V = L⁻ᵀ U.
        let l_inverse = mass_factor
            .l()
            .try_inverse()
            .expect("a Cholesky factor is invertible");
        let symmetric = &l_inverse * &reduced_stiffness * l_inverse.transpose();
        let eigen = (&symmetric + symmetric.transpose())
            .scale(0.5)
            .symmetric_eigen();
        // Ascending, so that the modes whose Coriolis couplings are kept come first.
        let mut order: Vec<usize> = (0..dofs).collect();
        order.sort_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
        let own_modes = l_inverse.transpose()
            * DMatrix::from_columns(
                &order
                    .iter()
                    .map(|&k| eigen.eigenvectors.column(k))
                    .collect::<Vec<_>>(),
            );
        let modal_squared: Vec<f64> = order
            .iter()
            .map(|&k| eigen.eigenvalues[k].max(0.0))
            .collect();
        let coriolis_modes = modal_squared
            .iter()
            .take_while(|l| CORIOLIS_TOLERANCE * l.sqrt() < 2.0 * rate_bound)
            .count();
        // What the couplings kept hold for: up to ε/2 times the first mode left out (at or
        // above the bound asked for).
        let rate_bound = modal_squared
            .get(coriolis_modes)
            .map_or(f64::INFINITY, |l| 0.5 * CORIOLIS_TOLERANCE * l.sqrt());
        let interface_modes = own_modes.rows(0, nb).into_owned();
        let kept_modes = own_modes.columns(0, coriolis_modes);
        let modal_gyroscopic =
            SkewMatrix::skew_part_of(&(kept_modes.transpose() * &gyroscopic * kept_modes));
        let modal_radial = own_modes.transpose() * &radial_reference;
        let modal_turning = own_modes.transpose() * &turning_reference;
        Ok(Self {
            interface,
            internal,
            held,
            mode_frequencies_hz: modes.iter().map(|m| m.frequency_hz).collect(),
            basis_internal,
            interface_reference,
            internal_reference,
            internal_mass,
            stiffness: reduced_stiffness,
            mass: reduced_mass,
            modes: own_modes,
            modal_squared,
            interface_modes,
            modal_gyroscopic,
            rate_bound,
            modal_radial,
            modal_turning,
            gyroscopic,
            turning_reference,
            radial_reference,
            reference_inertia,
        })
    }

    /// Reduced DOFs: two per interface node, one per mode and residual vector.
    pub fn dofs(&self) -> usize {
        self.stiffness.nrows()
    }

    /// Interface DOFs (the first entries of z).
    pub fn interface_dofs(&self) -> usize {
        2 * self.interface.len()
    }

    /// The own modes whose Coriolis couplings are kept (the first entries of η).
    pub fn coriolis_modes(&self) -> usize {
        self.modal_gyroscopic.dim()
    }

    /// The largest |ω| of the hub [rad/s] the kept Coriolis couplings hold for (module doc): ε/2
    /// times the first own mode left out, at or above the bound the block was built for.
    pub fn rate_bound(&self) -> f64 {
        self.rate_bound
    }

    /// A state at rest in the hub frame, undeformed.
    pub fn rest(&self) -> BlockState {
        let zero = vec![0.0; self.dofs()];
        BlockState {
            eta: zero.clone(),
            rate: zero.clone(),
            accel: zero,
        }
    }

    /// The state of reduced coordinates z and rates ż (η = Vᵀ M_red z).
    pub fn state_of(&self, z: &DVector<f64>, rate: &DVector<f64>) -> BlockState {
        let to_modal = |v: &DVector<f64>| -> Vec<f64> {
            (self.modes.transpose() * (&self.mass * v))
                .as_slice()
                .to_vec()
        };
        BlockState {
            eta: to_modal(z),
            rate: to_modal(rate),
            accel: vec![0.0; self.dofs()],
        }
    }

    /// The reduced coordinates z = V η of a modal vector.
    pub fn coordinates(&self, eta: &[f64]) -> DVector<f64> {
        &self.modes * DVector::from_column_slice(eta)
    }

    /// The interface nodes' displacements u_b = V_b η and rates u̇_b = V_b η̇ (hub frame, x
    /// and y per node), into `scratch` ([`BlockScratch::interface_displacement`],
    /// [`BlockScratch::interface_rate`]); the step's accelerations read them.
    pub fn interface_motion(&self, state: &BlockState, scratch: &mut BlockScratch) {
        let nb = self.interface_dofs();
        let (displacement, rate) = (&mut scratch.displacement, &mut scratch.displacement_rate);
        assert!(displacement.len() == nb && rate.len() == nb);
        widest::product_twice(
            &self.interface_modes,
            (&state.eta, &state.rate),
            (displacement, rate),
        );
    }

    /// The costly part of a step, whatever turns the hub, at the hub's `rate`, after
    /// [`Self::interface_motion`] of the same state: η̈ without the ω̇ term,
    /// y = V_bᵀ F_b − Ω² (η + β η̇) − 2ω Ĝ η̇ + ω² (m̂ + η), into `scratch.force`, s = ĝ + Ĝ η
    /// into `scratch.g_eta`, and the sums (I(η), s·y, s·s, (m̂ + η)·η̇, τ_b).
    /// [`Self::finish_prescribed`] or [`Self::finish_free`] then give η̈ in O(n), so a free
    /// hub's torque can be known later than the interface forces.
    pub fn prepare(
        &self,
        state: &BlockState,
        rate: f64,
        beta: f64,
        interface_force: &[f64],
        scratch: &mut BlockScratch,
    ) -> BlockSums {
        let (n, nb) = (self.dofs(), self.interface_dofs());
        assert_eq!(
            interface_force.len(),
            nb,
            "two force components per interface node"
        );
        let (eta, eta_rate) = (&state.eta, &state.rate);
        let BlockScratch {
            g_rate,
            g_eta,
            force,
            displacement: z_b,
            ..
        } = scratch;
        let r = self.coriolis_modes();
        widest::modal_products(
            &self.interface_modes,
            interface_force,
            &self.modal_gyroscopic,
            (&eta_rate[..r], &eta[..r]),
            (force, &mut g_rate[..r], &mut g_eta[..r]),
        );
        g_rate[r..].fill(0.0);
        g_eta[r..].fill(0.0);
        let w2 = rate * rate;
        let (mut inertia, mut s_y, mut s_s, mut radial_rate) =
            (self.reference_inertia, 0.0, 0.0, 0.0);
        for k in 0..n {
            let y = force[k]
                - self.modal_squared[k] * (eta[k] + beta * eta_rate[k])
                - 2.0 * rate * g_rate[k]
                + w2 * (self.modal_radial[k] + eta[k]);
            let s = self.modal_turning[k] + g_eta[k];
            force[k] = y;
            g_eta[k] = s;
            inertia += (2.0 * self.modal_radial[k] + eta[k]) * eta[k];
            s_y += s * y;
            s_s += s * s;
            radial_rate += (self.modal_radial[k] + eta[k]) * eta_rate[k];
        }
        let mut moment = 0.0;
        for (k, p) in self.interface_reference.iter().enumerate() {
            let (fx, fy) = (interface_force[2 * k], interface_force[2 * k + 1]);
            moment += (p.x + z_b[2 * k]) * fy - (p.y + z_b[2 * k + 1]) * fx;
        }
        BlockSums([inertia, s_y, s_s, radial_rate, moment])
    }

    /// η̈ with the hub turned as `frame` says, and the torque the hub applies to the block
    /// [N·m], after [`Self::interface_motion`] of the same state; `beta` is the
    /// stiffness-proportional damping coefficient [s], `interface_force` the forces on the
    /// interface nodes in the hub frame.
    pub fn accelerate_prescribed(
        &self,
        state: &mut BlockState,
        frame: FrameMotion,
        beta: f64,
        interface_force: &[f64],
        scratch: &mut BlockScratch,
    ) -> f64 {
        let sums = self.prepare(state, frame.rate, beta, interface_force, scratch);
        self.finish_prescribed(state, &sums, frame, scratch)
    }

    /// η̈ and ω̇ of a hub of inertia `hub_inertia` [kg·m²] turning at `rate` under the torque
    /// `torque` [N·m] (everything but the block's), solved together, after
    /// [`Self::interface_motion`] of the same state; returns ω̇.
    #[allow(clippy::too_many_arguments)]
    pub fn accelerate_free(
        &self,
        state: &mut BlockState,
        hub_inertia: f64,
        rate: f64,
        torque: f64,
        beta: f64,
        interface_force: &[f64],
        scratch: &mut BlockScratch,
    ) -> f64 {
        let sums = self.prepare(state, rate, beta, interface_force, scratch);
        self.finish_free(state, &sums, hub_inertia, rate, torque, scratch)
    }

    /// η̈ of a [`Self::prepare`]d state with the hub turned as `frame` says (its rate the
    /// prepared one); returns the torque the hub applies to the block [N·m].
    pub fn finish_prescribed(
        &self,
        state: &mut BlockState,
        sums: &BlockSums,
        frame: FrameMotion,
        scratch: &BlockScratch,
    ) -> f64 {
        let [inertia, s_y, s_s, radial_rate, moment] = sums.0;
        for ((a, y), s) in state
            .accel
            .iter_mut()
            .zip(&scratch.force)
            .zip(&scratch.g_eta)
        {
            *a = y - frame.accel * s;
        }
        // s·η̈ = s·y − ω̇ s·s
        inertia * frame.accel + s_y - frame.accel * s_s + 2.0 * frame.rate * radial_rate - moment
    }

    /// η̈ and ω̇ of a [`Self::prepare`]d state on a free hub of inertia `hub_inertia`
    /// [kg·m²] at the prepared `rate` under `torque` [N·m] (everything but the block's);
    /// returns ω̇.
    pub fn finish_free(
        &self,
        state: &mut BlockState,
        sums: &BlockSums,
        hub_inertia: f64,
        rate: f64,
        torque: f64,
        scratch: &BlockScratch,
    ) -> f64 {
        let [inertia, s_y, s_s, radial_rate, moment] = sums.0;
        // η̈ = y − ω̇ s in the hub equation (I_h + I) ω̇ + s·η̈ + 2ω (m̂ + η)·η̇ = τ + τ_b.
        let accel =
            (torque + moment - 2.0 * rate * radial_rate - s_y) / (hub_inertia + inertia - s_s);
        for ((a, y), s) in state
            .accel
            .iter_mut()
            .zip(&scratch.force)
            .zip(&scratch.g_eta)
        {
            *a = y - accel * s;
        }
        accel
    }

    /// Work space of the step's products, sized for this block.
    pub fn scratch(&self) -> BlockScratch {
        let n = self.dofs();
        let nb = self.interface_dofs();
        BlockScratch {
            g_rate: vec![0.0; n],
            g_eta: vec![0.0; n],
            force: vec![0.0; n],
            displacement: vec![0.0; nb],
            displacement_rate: vec![0.0; nb],
        }
    }

    /// I(η) = I_X + 2 m̂·η + η·η and s(η) = ĝ + Ĝ η.
    fn inertia_and_turning(&self, eta: &[f64]) -> (f64, DVector<f64>) {
        let r = self.coriolis_modes();
        let mut turning = self.modal_turning.clone();
        let coupled = DVector::from_vec(self.modal_gyroscopic.times(&eta[..r]));
        let mut kept = turning.rows_mut(0, r);
        kept += &coupled;
        let eta = DVector::from_column_slice(eta);
        let inertia = self.reference_inertia + 2.0 * self.modal_radial.dot(&eta) + eta.dot(&eta);
        (inertia, turning)
    }

    /// Kinetic energy ½ |η̇|² + ω s·η̇ + ½ ω² I(η) [J].
    pub fn kinetic_energy(&self, state: &BlockState, rate: f64) -> f64 {
        let (inertia, s) = self.inertia_and_turning(&state.eta);
        let eta_rate = DVector::from_column_slice(&state.rate);
        0.5 * eta_rate.dot(&eta_rate) + rate * s.dot(&eta_rate) + 0.5 * rate * rate * inertia
    }

    /// Σ Ω² x² (xᵀ K_red x in the block's own modes).
    fn stiffness_form(&self, x: &[f64]) -> f64 {
        self.modal_squared
            .iter()
            .zip(x)
            .map(|(w2, v)| w2 * v * v)
            .sum()
    }

    /// Strain energy ½ Σ Ω² η² [J].
    pub fn strain_energy(&self, state: &BlockState) -> f64 {
        0.5 * self.stiffness_form(&state.eta)
    }

    /// Power of the stiffness-proportional damping β Σ Ω² η̇² [W].
    pub fn damping_power(&self, state: &BlockState, beta: f64) -> f64 {
        beta * self.stiffness_form(&state.rate)
    }

    /// Angular momentum about the centre s·η̇ + ω I(η) [kg·m²/s].
    pub fn angular_momentum(&self, state: &BlockState, rate: f64) -> f64 {
        let (inertia, s) = self.inertia_and_turning(&state.eta);
        s.dot(&DVector::from_column_slice(&state.rate)) + rate * inertia
    }

    /// Displacements u (hub frame) of the internal nodes, x and y each, for reduced
    /// coordinates z.
    pub fn internal_displacements(&self, z: &DVector<f64>) -> DVector<f64> {
        &self.basis_internal * z
    }

    /// Reduced coordinates z of the displacements `interface` and `internal` (hub frame, x
    /// and y per node in the block's orders): u_b as given, the rest the M_ii-orthogonal
    /// projection of u_i − Ψ_i u_b on the modes and residual vectors (M_ii-closest with u_b
    /// held; exact when u lies in T's span).
    pub fn project(&self, interface: &[f64], internal: &[f64]) -> DVector<f64> {
        let nb = self.interface_dofs();
        assert!(interface.len() == nb && internal.len() == self.basis_internal.nrows());
        let mut z = DVector::zeros(self.dofs());
        z.rows_mut(0, nb).copy_from_slice(interface);
        let ub = DVector::from_column_slice(interface);
        let psi = self.basis_internal.columns(0, nb);
        let rest = DVector::from_column_slice(internal) - psi * ub;
        for j in nb..self.dofs() {
            let column = self.basis_internal.column(j);
            z[j] = (0..rest.len())
                .map(|k| self.internal_mass[k / 2] * column[k] * rest[k])
                .sum();
        }
        z
    }

    /// Reference positions of the interface nodes (hub frame) [m].
    pub fn interface_reference(&self) -> &[Point2<f64>] {
        &self.interface_reference
    }

    /// Reference positions of the internal nodes (hub frame) [m].
    pub fn internal_reference(&self) -> &[Point2<f64>] {
        &self.internal_reference
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::explicit::body::ExplicitBody;
    use crate::fe::modal::lowest_modes;
    use crate::mesh::GearMesh;
    use crate::samples;

    /// The 3000 rpm scene's window mesh of the paper's driver: six fine teeth, the explicit
    /// sizes; the block is every element of the other thirty sectors.
    fn window_mesh() -> Window {
        window_mesh_of(&samples::paper36_case(), 0)
    }

    /// A gear's mesh, its explicit body and which elements are in the block.
    type Window = (GearMesh, ExplicitBody, Vec<bool>);

    /// The paper's driver (36 teeth), the shifted 24/40 pair's pinion (24 teeth, x = +0.3) and
    /// its inverse's driver (40 teeth, x = −0.3), each with teeth 0–5 fine.
    fn windows() -> Vec<(&'static str, Window)> {
        vec![
            ("paper 36", window_mesh()),
            (
                "24/40's 24",
                window_mesh_of(&samples::shifted_24_40(false), 0),
            ),
            (
                "40/24's 40",
                window_mesh_of(&samples::shifted_24_40(true), 0),
            ),
        ]
    }

    /// The shifted 24/40 pair's pinion's window ([`window_mesh_of`]).
    fn pinion_24_window() -> Window {
        window_mesh_of(&samples::shifted_24_40(false), 0)
    }

    /// Gear `g` of `case` at the explicit sizes with teeth 0–5 fine, its body (the case's
    /// material on its face width) and the block: every element of the other sectors.
    fn window_mesh_of(case: &crate::case::Case, g: usize) -> Window {
        let mesh = samples::explicit_gear_mesh(case, g, (0..6).collect());
        let mut material = case.explicit_material();
        material.thickness = case.pair.gears[g].spec.face_width;
        let body = ExplicitBody::new(&mesh.nodes, &mesh.elements, material).unwrap();
        let in_block = mesh.element_fine.iter().map(|f| !f).collect();
        (mesh, body, in_block)
    }

    fn block_of(
        mesh: &GearMesh,
        body: &ExplicitBody,
        in_block: &[bool],
        cutoff: f64,
        rate_bound: f64,
    ) -> ReducedBlock {
        ReducedBlock::new(
            &mesh.nodes,
            &mesh.elements,
            in_block,
            &mesh.bore_nodes,
            &body.mass,
            &body.material,
            Cutoff::Hz(cutoff),
            rate_bound,
        )
        .unwrap()
    }

    /// The block's own stiffness triplets and the DOFs held or outside it.
    fn block_problem(
        mesh: &GearMesh,
        body: &ExplicitBody,
        in_block: &[bool],
        block: &ReducedBlock,
        hold_interface: bool,
    ) -> (Vec<(usize, usize, f64)>, Vec<usize>) {
        let (elements, _) = split_elements(&mesh.elements, in_block);
        let m = body.material;
        let d = elasticity_matrix(m.youngs_modulus, m.poisson_ratio, m.plane);
        let triplets = stiffness_triplets(&mesh.nodes, &elements, &d, m.thickness);
        let mut free = vec![false; mesh.nodes.len()];
        block.internal.iter().for_each(|&i| free[i] = true);
        if !hold_interface {
            block.interface.iter().for_each(|&i| free[i] = true);
        }
        let fixed = (0..2 * mesh.nodes.len()).filter(|d| !free[d / 2]).collect();
        (triplets, fixed)
    }

    /// Static loads on the interface: the reduced block gives the full block's interface
    /// displacements to round-off (the constraint modes span every such state), and its
    /// internal displacements too.
    #[test]
    fn an_interface_load_gives_the_full_blocks_displacements() {
        for (name, (mesh, body, in_block)) in windows() {
            let block = block_of(&mesh, &body, &in_block, 20e3, f64::INFINITY);
            let (triplets, fixed) = block_problem(&mesh, &body, &in_block, &block, false);
            let n = 2 * mesh.nodes.len();
            let full = FactorizedStiffness::new(n, triplets, &fixed).unwrap();
            let nb = block.interface_dofs();
            // A load of varied directions and sizes on every interface node, net moment included.
            let load_b: Vec<f64> = (0..nb)
                .map(|j| 1e3 * (1.0 + 0.37 * j as f64).sin())
                .collect();
            let mut load = vec![0.0; n];
            for (k, &node) in block.interface.iter().enumerate() {
                load[2 * node] = load_b[2 * k];
                load[2 * node + 1] = load_b[2 * k + 1];
            }
            let u = full.solve(&load);
            let mut q = DVector::zeros(block.dofs());
            q.rows_mut(0, nb).copy_from_slice(&load_b);
            let z = block.stiffness.clone().cholesky().unwrap().solve(&q);
            let scale = u.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            let mut worst: f64 = 0.0;
            for (k, &node) in block.interface.iter().enumerate() {
                for c in 0..2 {
                    worst = worst.max((z[2 * k + c] - u[2 * node + c]).abs());
                }
            }
            let internal = block.internal_displacements(&z);
            for (k, &node) in block.internal.iter().enumerate() {
                for c in 0..2 {
                    worst = worst.max((internal[2 * k + c] - u[2 * node + c]).abs());
                }
            }
            assert!(
                worst < 1e-8 * scale,
                "{name}: worst {worst:.3e} m of {scale:.3e} m"
            );
        }
    }

    /// A field in T's span projected back gives its reduced coordinates, and the modal state
    /// of z gives z back.
    #[test]
    fn a_reduced_field_projects_back_to_its_coordinates() {
        let (mesh, body, in_block) = window_mesh();
        let block = block_of(&mesh, &body, &in_block, 20e3, f64::INFINITY);
        let z = DVector::from_fn(block.dofs(), |k, _| 1e-7 * (0.3 + 0.71 * k as f64).sin());
        let nb = block.interface_dofs();
        let internal = block.internal_displacements(&z);
        let back = block.project(&z.as_slice()[..nb], internal.as_slice());
        assert!(
            (&back - &z).amax() < 1e-9 * z.amax(),
            "{:.3e}",
            (&back - &z).amax()
        );
        let state = block.state_of(&z, &z);
        let again = block.coordinates(&state.eta);
        assert!(
            (&again - &z).amax() < 1e-9 * z.amax(),
            "{:.3e}",
            (&again - &z).amax()
        );
    }

    /// The centrifugal load at 3000 rpm on a held interface: the residual vector holds the
    /// full block's static response, (K_ii − ω² M_ii) u = ω² M_ii X, to within the spin
    /// softening's share of it, (ω/ω₁)² ≈ 1.4e-5 at most (ω₁ the first fixed-interface mode;
    /// measured: 3.2e-14 m of a 7.8e-8 m stretch on the paper's driver, 4.3e-15 of 1.7e-8 m on
    /// 24/40's pinion, 5.5e-14 of 1.1e-7 m on 40/24's 40-tooth gear: 2.5–5e-7).
    #[test]
    fn the_centrifugal_load_gives_the_full_blocks_stretch() {
        for (name, (mesh, body, in_block)) in windows() {
            let block = block_of(&mesh, &body, &in_block, 20e3, f64::INFINITY);
            let (triplets, fixed) = block_problem(&mesh, &body, &in_block, &block, true);
            let n = 2 * mesh.nodes.len();
            let omega = 3000.0 * std::f64::consts::TAU / 60.0;
            let w2 = omega * omega;
            let softened: Vec<(usize, usize, f64)> = triplets
                .into_iter()
                .chain((0..n).map(|d| (d, d, -w2 * body.mass[d / 2])))
                .collect();
            let full = FactorizedStiffness::new(n, softened, &fixed).unwrap();
            let load: Vec<f64> = (0..n)
                .map(|d| w2 * body.mass[d / 2] * mesh.nodes[d / 2][d % 2])
                .collect();
            let u = full.solve(&load);
            // The reduced block, interface held: only the modes and residual vectors move.
            let nb = block.interface_dofs();
            let rest = block.dofs() - nb;
            let k = block.stiffness.view((nb, nb), (rest, rest))
                - block.mass.view((nb, nb), (rest, rest)) * w2;
            let q = block.radial_reference.rows(nb, rest) * w2;
            let z_rest = k.cholesky().unwrap().solve(&q);
            let mut z = DVector::zeros(block.dofs());
            z.rows_mut(nb, rest).copy_from(&z_rest);
            let internal = block.internal_displacements(&z);
            let scale = u.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            let worst = block
                .internal
                .iter()
                .enumerate()
                .flat_map(|(k, &node)| (0..2).map(move |c| (k, node, c)))
                .map(|(k, node, c)| (internal[2 * k + c] - u[2 * node + c]).abs())
                .fold(0.0_f64, f64::max);
            eprintln!("{name}: centrifugal stretch {scale:.3e} m, worst difference {worst:.3e} m");
            assert!(scale > 1e-8, "{name}: a stretch of {scale:.3e} m");
            assert!(
                worst < 1.4e-5 * scale,
                "{name}: worst {worst:.3e} m of {scale:.3e} m"
            );
        }
    }

    /// The block with its interface free (held at the bore only): the reduced frequencies are
    /// Rayleigh–Ritz upper bounds of the full block's, and come down to them as the cutoff
    /// rises (measured, lowest two: paper's driver 9.6 / 12.1 kHz within 0.03 / 0.51 % at a
    /// 40 kHz cutoff and 0.004 / 0.046 % at 80 kHz; 24/40's pinion 24.7 / 26.4 kHz, 0.26 / 2.6 %
    /// and 0.11 / 0.19 %; 40/24's 40-tooth gear 7.8 / 10.3 kHz, 0.017 / 0.23 % and 0.002 /
    /// 0.032 %; asserted: upper bounds, nearer at 80 kHz than at 40 kHz, within 0.2 % at 80 kHz).
    #[test]
    fn the_reduced_frequencies_bound_the_full_blocks_from_above() {
        for (name, (mesh, body, in_block)) in windows() {
            let coarse = block_of(&mesh, &body, &in_block, 40e3, f64::INFINITY);
            let (triplets, fixed) = block_problem(&mesh, &body, &in_block, &coarse, false);
            // The full block on its free DOFs, renumbered.
            let n = 2 * mesh.nodes.len();
            let mut is_fixed = vec![false; n];
            fixed.iter().for_each(|&d| is_fixed[d] = true);
            let mut index = vec![usize::MAX; n];
            let mut free = 0;
            for d in (0..n).filter(|&d| !is_fixed[d]) {
                index[d] = free;
                free += 1;
            }
            let k: Vec<(usize, usize, f64)> = triplets
                .iter()
                .filter(|&&(r, c, _)| !is_fixed[r] && !is_fixed[c])
                .map(|&(r, c, v)| (index[r], index[c], v))
                .collect();
            let m: Vec<(usize, usize, f64)> = (0..n)
                .filter(|&d| !is_fixed[d])
                .map(|d| (index[d], index[d], body.mass[d / 2]))
                .collect();
            let full: Vec<f64> = lowest_modes(free, &k, &m, 4, 0.0)
                .unwrap()
                .iter()
                .map(|m| m.frequency_hz)
                .collect();
            let reduced = |block: &ReducedBlock| -> Vec<f64> {
                let l_inv = block
                    .mass
                    .clone()
                    .cholesky()
                    .unwrap()
                    .l()
                    .try_inverse()
                    .unwrap();
                let mut f: Vec<f64> = (&l_inv * &block.stiffness * l_inv.transpose())
                    .symmetric_eigen()
                    .eigenvalues
                    .iter()
                    .map(|e| e.max(0.0).sqrt() / std::f64::consts::TAU)
                    .collect();
                f.sort_by(f64::total_cmp);
                f
            };
            let fine = block_of(&mesh, &body, &in_block, 80e3, f64::INFINITY);
            let (at_40, at_80) = (reduced(&coarse), reduced(&fine));
            for (k, f) in full.iter().take(2).enumerate() {
                let (e40, e80) = (at_40[k] / f - 1.0, at_80[k] / f - 1.0);
                eprintln!(
                    "{name}: {f:.1} Hz: {:+.4} % at 40 kHz, {:+.4} % at 80 kHz",
                    100.0 * e40,
                    100.0 * e80
                );
                assert!(
                    e40 > -1e-9 && e80 > -1e-9,
                    "{name}: below the full block's {f} Hz"
                );
                assert!(
                    e80 < e40 && e80 < 2e-3,
                    "{name}: {f} Hz: {e40:.3e} at 40 kHz, {e80:.3e} at 80 kHz"
                );
            }
        }
    }

    /// A free hub carrying the block, spun and released with a deformed block and no torque:
    /// the angular momentum s(z)ᵀż + (I_h + I(z)) ω and the energy stay what they were, to
    /// the central difference's order: its velocity terms (Coriolis, the hub's) taken at the
    /// half step make the momentum's error O(Δt) and leave the energy's O(Δt²). This checks
    /// the coupled hub solve and the Euler and centrifugal terms' consistency with the energy;
    /// the Coriolis term does no work and conserves the momentum whatever its sign, so the
    /// full-body comparison checks it. Measured at a
    /// step of 1/40 of the highest reduced mode's period over 0.4 ms: 1.0e-6 and 1.9e-6, at
    /// half the step 5.1e-7 and 5.1e-7; asserted: below 2e-6 / 4e-6, and halving the step
    /// divides them by 2 / 4 within 20 %. The same (to three digits) with the Coriolis
    /// couplings of a hub bound of twice the spin only, the block's kept modes and its rate
    /// bound asserted as [`ReducedBlock::new`] states them.
    #[test]
    fn a_free_spinning_block_keeps_its_angular_momentum_and_energy() {
        let (mesh, body, in_block) = window_mesh();
        // Every Coriolis coupling, and those of a bound of twice the spin (truncated).
        for rate_bound in [f64::INFINITY, 600.0] {
            let block = block_of(&mesh, &body, &in_block, 20e3, rate_bound);
            if rate_bound.is_finite() {
                // Kept: the modes below 2 ω_max/ε; held for: ε/2 times the first left out.
                let r = block.coriolis_modes();
                assert!(0 < r && r < block.dofs(), "{r} of {}", block.dofs());
                let first_out = block.modal_squared[r].sqrt();
                assert!(CORIOLIS_TOLERANCE * block.modal_squared[r - 1].sqrt() < 2.0 * rate_bound);
                assert!(CORIOLIS_TOLERANCE * first_out >= 2.0 * rate_bound);
                assert_eq!(block.rate_bound(), 0.5 * CORIOLIS_TOLERANCE * first_out);
            }
            a_free_spinning_block_keeps_them(&block);
        }
    }

    /// [`a_free_spinning_block_keeps_its_angular_momentum_and_energy`] on `block`.
    fn a_free_spinning_block_keeps_them(block: &ReducedBlock) {
        let hub_inertia = 1e-3;
        // An initial deformation: the last residual vector (the angular acceleration's) and an
        // interface shear.
        let last = block.dofs() - 1;
        let mut z = DVector::zeros(block.dofs());
        z[last] = 2e-4 * block.mass[(last, last)].sqrt().recip();
        for k in 0..block.interface.len() {
            z[2 * k] = 1e-7;
        }
        let start = block.state_of(&z, &DVector::zeros(block.dofs()));
        let zero = vec![0.0; block.interface_dofs()];
        let momentum = |s: &BlockState, w: f64| block.angular_momentum(s, w) + hub_inertia * w;
        let energy = |s: &BlockState, w: f64| {
            block.kinetic_energy(s, w) + block.strain_energy(s) + 0.5 * hub_inertia * w * w
        };
        let top = block
            .modal_squared
            .iter()
            .fold(0.0_f64, |m, w| m.max(*w))
            .sqrt();
        let duration = 4e-4;
        let run = |dt: f64| {
            let mut scratch = block.scratch();
            let mut state = start.clone();
            let mut rate = 300.0;
            block.interface_motion(&state, &mut scratch);
            let mut accel =
                block.accelerate_free(&mut state, hub_inertia, rate, 0.0, 0.0, &zero, &mut scratch);
            let (h0, e0) = (momentum(&state, rate), energy(&state, rate));
            let (mut worst_h, mut worst_e): (f64, f64) = (0.0, 0.0);
            for _ in 0..(duration / dt).round() as usize {
                rate += 0.5 * dt * accel;
                state.drift(dt);
                block.interface_motion(&state, &mut scratch);
                accel = block.accelerate_free(
                    &mut state,
                    hub_inertia,
                    rate,
                    0.0,
                    0.0,
                    &zero,
                    &mut scratch,
                );
                rate += 0.5 * dt * accel;
                state.kick(0.5 * dt);
                worst_h = worst_h.max((momentum(&state, rate) / h0 - 1.0).abs());
                worst_e = worst_e.max((energy(&state, rate) / e0 - 1.0).abs());
            }
            (worst_h, worst_e)
        };
        let dt = std::f64::consts::TAU / top / 40.0;
        let (h1, e1) = run(dt);
        let (h2, e2) = run(0.5 * dt);
        eprintln!("dt {dt:.3e} s: momentum {h1:.3e} energy {e1:.3e}; half: {h2:.3e} {e2:.3e}");
        assert!(h1 < 2e-6 && e1 < 4e-6, "momentum {h1:.3e}, energy {e1:.3e}");
        // The velocity terms at the half step: O(Δt) in the momentum, O(Δt²) in the energy.
        for (what, coarse, fine, order) in [("momentum", h1, h2, 2.0), ("energy", e1, e2, 4.0)] {
            let ratio = coarse / fine;
            assert!(
                (ratio / order - 1.0).abs() < 0.2,
                "{what}: halving the step divides by {ratio:.2}, not {order}"
            );
        }
    }

    /// How the hub turns in [`turning_comparison`]: θ = ω₀ t + ½ ω̇ t².
    #[derive(Clone, Copy)]
    struct Turning {
        /// The gear and its block ([`window_mesh`], [`pinion_24_window`]).
        window: fn() -> Window,
        rpm: f64,
        /// The block's cutoff [Hz].
        cutoff: f64,
        accel: f64,
        /// Coriolis sign of the reduced block's equations (1: as derived; −1 flips it, to show
        /// the comparison sees it).
        coriolis: f64,
    }

    /// The window mesh turning about its held bore as `turning` says, undeformed at the start
    /// (so the centrifugal load rings), loaded on a fine flank by a force raised smoothly to
    /// 2 kN over 0.1 ms: the fine sectors integrated as the explicit pair does (velocity
    /// Verlet, corotational elements, stiffness-proportional damping) with the block reduced
    /// (at `turning.cutoff`), against all elements integrated so. Returns the largest differences
    /// over 0.3 ms, relative to the largest values, of the loaded node's and an interface
    /// node's displacement in the hub frame and of the hub's torque. The bore nodes ride on
    /// the hub with their whole masses in both (the block leaves them out).
    fn turning_comparison(turning: Turning) -> [f64; 3] {
        let histories = turning_histories(turning, &[f64::INFINITY]);
        let (worst, largest) = largest_differences(&histories[1], &histories[0]);
        let steps = histories[0].len();
        eprintln!(
            "{:.0} rpm, {:.1e} rad/s², Coriolis {:+}: {steps} steps: loaded node {:.3e} of {:.3e} m, interface node {:.3e} of {:.3e} m, torque {:.3e} of {:.3e} N m",
            turning.rpm, turning.accel, turning.coriolis, worst[0], largest[0], worst[1], largest[1], worst[2], largest[2]
        );
        std::array::from_fn(|k| worst[k] / largest[k])
    }

    /// A step's record of [`turning_histories`]: the loaded node's and the watched interface
    /// node's displacements in the hub frame [m], and the hub's torque [N·m].
    type Sample = ([f64; 2], [f64; 2], f64);

    /// The largest differences of `got` from `expected` in each of a [`Sample`]'s three
    /// quantities, and `expected`'s largest values.
    fn largest_differences(got: &[Sample], expected: &[Sample]) -> ([f64; 3], [f64; 3]) {
        let mut worst = [0.0_f64; 3];
        let mut largest = [0.0_f64; 3];
        for (got, expected) in got.iter().zip(expected) {
            let pairs = [
                (
                    (got.0[0] - expected.0[0]).hypot(got.0[1] - expected.0[1]),
                    expected.0[0].hypot(expected.0[1]),
                ),
                (
                    (got.1[0] - expected.1[0]).hypot(got.1[1] - expected.1[1]),
                    expected.1[0].hypot(expected.1[1]),
                ),
                ((got.2 - expected.2).abs(), expected.2.abs()),
            ];
            for (k, (error, size)) in pairs.into_iter().enumerate() {
                worst[k] = worst[k].max(error);
                largest[k] = largest[k].max(size);
            }
        }
        (worst, largest)
    }

    /// [`turning_comparison`]'s runs: the full body's history first, then the reduced
    /// block's with its Coriolis couplings kept for each of `rate_bounds` [rad/s].
    fn turning_histories(turning: Turning, rate_bounds: &[f64]) -> Vec<Vec<Sample>> {
        use crate::explicit::solver::critical_step;
        let (mesh, full, in_block) = (turning.window)();
        let (_, fine_elements) = split_elements(&mesh.elements, &in_block);
        let fine = ExplicitBody::new(&mesh.nodes, &fine_elements, full.material).unwrap();
        let n = mesh.nodes.len();
        let mut bore = vec![false; n];
        mesh.bore_nodes.iter().for_each(|&i| bore[i] = true);
        let fixed: Vec<bool> = (0..2 * n).map(|d| bore[d / 2]).collect();
        let dt = 0.8 * critical_step(&full, &fixed, 200);
        let beta = 1.3e-9;
        let omega0 = turning.rpm * std::f64::consts::TAU / 60.0;
        let motion = |t: f64| FrameMotion {
            rate: omega0 + turning.accel * t,
            accel: turning.accel,
        };
        let angle = |t: f64| omega0 * t + 0.5 * turning.accel * t * t;
        let flank = &mesh.flanks.iter().find(|f| f.tooth == 2).unwrap().nodes;
        let loaded = flank[flank.len() / 2];
        let interface = BlockNodes::of(
            mesh.nodes.len(),
            &mesh.elements,
            &in_block,
            &mesh.bore_nodes,
        )
        .interface;
        let watched = interface.len() / 3;
        let watched_node = interface[watched];
        let x_ref = mesh.nodes[loaded];
        // Against the turning, along the tangent at the loaded node, in the hub frame.
        let direction = [
            x_ref.y / x_ref.coords.norm(),
            -x_ref.x / x_ref.coords.norm(),
        ];
        let ramp = 1e-4;
        let force = |t: f64| {
            2e3 * if t < ramp {
                0.5 - 0.5 * (std::f64::consts::PI * t / ramp).cos()
            } else {
                1.0
            }
        };
        let turn = |theta: f64, p: [f64; 2]| {
            let (s, c) = theta.sin_cos();
            [c * p[0] - s * p[1], s * p[0] + c * p[1]]
        };
        let steps = (3e-4 / dt).round() as usize;
        let rigid = || -> (Vec<f64>, Vec<f64>) {
            let x: Vec<f64> = mesh.nodes.iter().flat_map(|p| [p.x, p.y]).collect();
            let v = x
                .chunks_exact(2)
                .flat_map(|p| [-omega0 * p[1], omega0 * p[0]])
                .collect();
            (x, v)
        };
        let local = |x: &[f64], theta: f64, node: usize| {
            let p = turn(-theta, [x[2 * node], x[2 * node + 1]]);
            [p[0] - mesh.nodes[node].x, p[1] - mesh.nodes[node].y]
        };
        // x = R X, v = ω J x, a = ω̇ J x − ω² x.
        let place_bore = |t: f64, x: &mut [f64], v: &mut [f64], a: &mut [f64]| {
            let (theta, m) = (angle(t), motion(t));
            for &i in &mesh.bore_nodes {
                let p = turn(theta, [mesh.nodes[i].x, mesh.nodes[i].y]);
                x[2 * i..2 * i + 2].copy_from_slice(&p);
                v[2 * i] = -m.rate * p[1];
                v[2 * i + 1] = m.rate * p[0];
                a[2 * i] = -m.accel * p[1] - m.rate * m.rate * p[0];
                a[2 * i + 1] = m.accel * p[0] - m.rate * m.rate * p[1];
            }
        };
        // The hub's torque on the bore nodes, m a − f (whole masses), about the centre.
        let bore_torque = |x: &[f64], a: &[f64], f: &[f64]| -> f64 {
            mesh.bore_nodes
                .iter()
                .map(|&i| {
                    let m = full.mass[i];
                    let r = [m * a[2 * i] - f[2 * i], m * a[2 * i + 1] - f[2 * i + 1]];
                    x[2 * i] * r[1] - x[2 * i + 1] * r[0]
                })
                .sum()
        };
        let load = |t: f64, f: &mut [f64]| {
            let p = turn(angle(t), direction.map(|c| c * force(t)));
            f[2 * loaded] += p[0];
            f[2 * loaded + 1] += p[1];
        };

        // All elements.
        let (mut x, mut v) = rigid();
        let mut a = vec![0.0; 2 * n];
        let mut f = vec![0.0; 2 * n];
        place_bore(0.0, &mut x, &mut v, &mut a);
        let mut full_history = Vec::with_capacity(steps);
        for step in 1..=steps {
            let t = step as f64 * dt;
            for d in (0..2 * n).filter(|&d| !fixed[d]) {
                v[d] += 0.5 * dt * a[d];
                x[d] += dt * v[d];
            }
            place_bore(t, &mut x, &mut v, &mut a);
            f.iter_mut().for_each(|fi| *fi = 0.0);
            full.internal_forces(&x, &v, beta, &mut f);
            load(t, &mut f);
            for d in (0..2 * n).filter(|&d| !fixed[d]) {
                a[d] = f[d] / full.mass[d / 2];
                v[d] += 0.5 * dt * a[d];
            }
            let torque = bore_torque(&x, &a, &f);
            let theta = angle(t);
            full_history.push((
                local(&x, theta, loaded),
                local(&x, theta, watched_node),
                torque,
            ));
        }

        // The fine sectors with the block reduced; the block's η̈ at the start from its
        // equations (the full body's free nodes start at a = 0 in the inertial frame, so
        // ü = ω² X in the hub frame: the same state).
        let reduced_history = |block: &ReducedBlock| -> Vec<Sample> {
            let mut owned = vec![false; n];
            fine_elements
                .iter()
                .flatten()
                .for_each(|&i| owned[i] = true);
            block
                .interface
                .iter()
                .chain(&mesh.bore_nodes)
                .for_each(|&i| owned[i] = false);
            let owned_dofs: Vec<usize> = (0..2 * n).filter(|&d| owned[d / 2]).collect();
            let (mut x, mut v) = rigid();
            let mut a = vec![0.0; 2 * n];
            let mut f = vec![0.0; 2 * n];
            place_bore(0.0, &mut x, &mut v, &mut a);
            let mut state = block.rest();
            let mut scratch = block.scratch();
            let nb = block.interface_dofs();
            let mut interface_force = vec![0.0; nb];
            block.interface_motion(&state, &mut scratch);
            block.accelerate_prescribed(
                &mut state,
                motion(0.0),
                beta,
                &interface_force,
                &mut scratch,
            );
            let mut history = Vec::with_capacity(steps);
            for step in 1..=steps {
                let t = step as f64 * dt;
                let (theta, frame) = (angle(t), motion(t));
                for &d in &owned_dofs {
                    v[d] += 0.5 * dt * a[d];
                    x[d] += dt * v[d];
                }
                state.drift(dt);
                place_bore(t, &mut x, &mut v, &mut a);
                block.interface_motion(&state, &mut scratch);
                let (u_b, rate_b) = (scratch.interface_displacement(), scratch.interface_rate());
                for (k, (&i, p)) in block
                    .interface
                    .iter()
                    .zip(block.interface_reference())
                    .enumerate()
                {
                    let y = [p.x + u_b[2 * k], p.y + u_b[2 * k + 1]];
                    let u = [
                        rate_b[2 * k] - frame.rate * y[1],
                        rate_b[2 * k + 1] + frame.rate * y[0],
                    ];
                    x[2 * i..2 * i + 2].copy_from_slice(&turn(theta, y));
                    v[2 * i..2 * i + 2].copy_from_slice(&turn(theta, u));
                }
                f.iter_mut().for_each(|fi| *fi = 0.0);
                fine.internal_forces(&x, &v, beta, &mut f);
                load(t, &mut f);
                for &d in &owned_dofs {
                    a[d] = f[d] / full.mass[d / 2];
                    v[d] += 0.5 * dt * a[d];
                }
                for (k, &i) in block.interface.iter().enumerate() {
                    let local_force = turn(-theta, [f[2 * i], f[2 * i + 1]]);
                    interface_force[2 * k..2 * k + 2].copy_from_slice(&local_force);
                }
                let block_torque = block.accelerate_prescribed(
                    &mut state,
                    frame,
                    beta,
                    &interface_force,
                    &mut scratch,
                );
                state.kick(0.5 * dt);
                let torque = bore_torque(&x, &a, &f) + block_torque;
                block.interface_motion(&state, &mut scratch);
                let u_b = scratch.interface_displacement();
                history.push((
                    local(&x, theta, loaded),
                    [u_b[2 * watched], u_b[2 * watched + 1]],
                    torque,
                ));
            }
            history
        };
        let mut histories = vec![full_history];
        for &rate_bound in rate_bounds {
            let mut block = block_of(&mesh, &full, &in_block, turning.cutoff, rate_bound);
            block.modal_gyroscopic.scale(turning.coriolis);
            histories.push(reduced_history(&block));
        }
        histories
    }

    /// The step's product with a skew-symmetric matrix held by its upper triangle is the dense
    /// product of the same matrix (to round-off: 1e-13 of |A| |x|) at sizes around the lane
    /// width and at a block's size, and the dispatch to this CPU's widest vector unit gives the
    /// same bits as the portable build; the triangle is exactly the skew part.
    #[test]
    fn the_skew_product_is_the_dense_product() {
        for n in [0, 1, 2, 7, 8, 9, 16, 17, 31, 64, 293] {
            let general = DMatrix::from_fn(n, n, |i, j| ((3 * i + 7 * j + 1) as f64).sin());
            let skew = SkewMatrix::skew_part_of(&general);
            let dense = (&general - general.transpose()) * 0.5;
            assert_eq!(skew.to_dense(), dense, "n = {n}");
            let x1: Vec<f64> = (0..n).map(|k| (0.3 * k as f64).cos()).collect();
            let x2: Vec<f64> = (0..n).map(|k| 1.0 + (0.7 * k as f64).sin()).collect();
            let (mut y1, mut y2) = (vec![f64::NAN; n], vec![f64::NAN; n]);
            super::skew_product_twice(&skew, (&x1, &x2), (&mut y1, &mut y2));
            let (mut w1, mut w2) = (vec![f64::NAN; n], vec![f64::NAN; n]);
            widest::skew_product_twice(&skew, (&x1, &x2), (&mut w1, &mut w2));
            let bits = |v: &[f64]| v.iter().map(|a| a.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&y1), bits(&w1), "n = {n}");
            assert_eq!(bits(&y2), bits(&w2), "n = {n}");
            assert_eq!(bits(&skew.times(&x1)), bits(&y1), "n = {n}");
            for (x, y) in [(&x1, &y1), (&x2, &y2)] {
                let exact = &dense * DVector::from_column_slice(x);
                let scale = dense.norm() * x.iter().map(|a| a * a).sum::<f64>().sqrt();
                for (a, b) in y.iter().zip(exact.iter()) {
                    assert!(
                        (a - b).abs() <= 1e-13 * scale.max(1e-300),
                        "n = {n}: {a} {b}"
                    );
                }
            }
        }
    }

    /// [`turning_comparison`] at 3000 rpm: the loaded node, the interface node and the hub's
    /// torque within 0.5 % of the full body's (measured: 0.055 %, 0.18 %, 0.024 %; the
    /// corotational elements against the block's one frame, the modes above the cutoff). The
    /// same with the Coriolis term's sign flipped misses the torque by 1.06 % (the test sees
    /// the term, which is about 2ω/Ω₁ ≈ 1 % of the elastic forces here; at 12 000 rpm the
    /// flipped sign misses it by 65 %, the right one by 0.17 %).
    #[test]
    fn the_reduced_block_turns_and_rings_as_the_full_body() {
        let turning = Turning {
            window: window_mesh,
            rpm: 3000.0,
            cutoff: 80e3,
            accel: 0.0,
            coriolis: 1.0,
        };
        let errors = turning_comparison(turning);
        assert!(
            errors.iter().all(|e| *e < 5e-3),
            "relative errors {errors:?}"
        );
        let flipped = turning_comparison(Turning {
            coriolis: -1.0,
            ..turning
        });
        assert!(
            flipped[2] > 5e-3,
            "the flipped Coriolis term unseen: {flipped:?}"
        );
    }

    /// The hub spun up from 3000 rpm at 2e5 rad/s² (to 3570 rpm in 0.3 ms), the step of ω̇ at
    /// the start ringing through every mode: the Euler terms, the block's share of the hub
    /// torque (I ω̇ and s·η̈) and the bore's inertia as in [`turning_comparison`]'s contract,
    /// within 0.5 % (measured: 0.086 %, 0.12 %, 0.33 %: the torque's ringing in the modes above
    /// the cutoff, which the reduced block leaves out).
    #[test]
    fn the_reduced_block_spins_up_as_the_full_body() {
        let errors = turning_comparison(Turning {
            window: window_mesh,
            rpm: 3000.0,
            cutoff: 80e3,
            accel: 2e5,
            coriolis: 1.0,
        });
        assert!(
            errors.iter().all(|e| *e < 5e-3),
            "relative errors {errors:?}"
        );
    }

    /// The Coriolis couplings a block leaves out (module doc), on the spin-up of
    /// [`the_reduced_block_spins_up_as_the_full_body`]: with the bound the explicit pair sets
    /// (twice the speed) the block keeps Ĝ among fewer than half of its own modes (61 of 143),
    /// and its run differs from the run with every coupling kept by less than 1 % of what
    /// leaving out every coupling moves it (measured: 2.8e-7, 8.4e-7 and 1.5e-7 of the largest
    /// values of the loaded node's, the interface node's motion and the hub torque, against
    /// 1.7e-4, 3.1e-4, 6.2e-4 with none kept): the couplings left out carry under 1 % of the
    /// Coriolis term's effect at this speed.
    #[test]
    fn the_coriolis_couplings_left_out_move_the_block_within_their_bound() {
        let turning = Turning {
            window: window_mesh,
            rpm: 3000.0,
            cutoff: 80e3,
            accel: 2e5,
            coriolis: 1.0,
        };
        let bound = 2.0 * turning.rpm * std::f64::consts::TAU / 60.0;
        let (mesh, body, in_block) = window_mesh();
        let block = block_of(&mesh, &body, &in_block, turning.cutoff, bound);
        assert!(
            2 * block.coriolis_modes() < block.dofs(),
            "{} of {} modes coupled",
            block.coriolis_modes(),
            block.dofs()
        );
        let histories = turning_histories(turning, &[f64::INFINITY, bound, 0.0]);
        let relative = |k: usize| -> [f64; 3] {
            let (worst, largest) = largest_differences(&histories[k], &histories[1]);
            std::array::from_fn(|q| worst[q] / largest[q])
        };
        let (kept, none) = (relative(2), relative(3));
        eprintln!(
            "{} of {} modes coupled: {:?} of the largest values; none coupled: {:?}",
            block.coriolis_modes(),
            block.dofs(),
            kept.map(|e| format!("{e:.2e}")),
            none.map(|e| format!("{e:.2e}"))
        );
        assert!(
            kept.iter().zip(&none).all(|(k, n)| *k < 0.01 * n),
            "{kept:?} against {none:?}"
        );
    }

    /// [`turning_comparison`] on the shifted 24/40 pair's pinion (24 teeth, x = +0.3) at
    /// 3000 rpm. Its block (18 sectors) is smaller and stiffer than the paper's, so fewer of its
    /// modes lie below a cutoff; the differences shrink as the cutoff rises (measured: loaded
    /// node / interface node / torque 0.087 / 0.73 / 0.059 % at 80 kHz, 0.034 / 0.45 / 0.0078 %
    /// at 160 kHz, the interface node's motion 1.3e-7 m, a quarter of the paper driver's):
    /// asserted, every difference smaller at 160 kHz, and within 0.5 % there. The cutoff must
    /// follow the gear when the block is wired.
    #[test]
    fn the_reduced_block_of_a_shifted_pinion_converges_to_its_full_body() {
        let at = |cutoff: f64| {
            turning_comparison(Turning {
                window: pinion_24_window,
                rpm: 3000.0,
                cutoff,
                accel: 0.0,
                coriolis: 1.0,
            })
        };
        let (coarse, fine) = (at(80e3), at(160e3));
        assert!(
            fine.iter().zip(&coarse).all(|(f, c)| f < c),
            "not converging: {coarse:?} at 80 kHz, {fine:?} at 160 kHz"
        );
        assert!(fine.iter().all(|e| *e < 5e-3), "relative errors {fine:?}");
    }

    /// The fine sectors' lowest mode that sets the cutoff is theirs held at the block and the
    /// bore: the same as the lowest fixed-interface mode of the fine sectors taken as a block
    /// themselves (another path: [`ReducedBlock::new`]'s node split and fixed-interface
    /// problem), on the three test gears; and on the paper's driver it drops as the window's
    /// fine sector widens (six fine teeth against three: the sector, not one tooth, vibrates).
    #[test]
    fn the_fine_sectors_lowest_mode_is_their_fixed_interface_fundamental() {
        let of = |mesh: &GearMesh, body: &ExplicitBody, in_block: &[bool]| {
            lowest_mode_beside_block(
                &mesh.nodes,
                &mesh.elements,
                in_block,
                &mesh.bore_nodes,
                &body.mass,
                &body.material,
            )
            .unwrap()
        };
        for (name, (mesh, body, in_block)) in windows() {
            let beside = of(&mesh, &body, &in_block);
            let fine: Vec<bool> = in_block.iter().map(|b| !b).collect();
            let as_block = block_of(&mesh, &body, &fine, 1.5 * beside, f64::INFINITY);
            let lowest = as_block.mode_frequencies_hz[0];
            eprintln!("{name}: the fine sectors' lowest {beside:.1} Hz, as a block {lowest:.1} Hz");
            // Both converged far below 1e-6 in frequency (Lanczos residuals 1e-9 and 1e-4).
            assert!(
                (lowest / beside - 1.0).abs() < 1e-6,
                "{name}: {beside} against {lowest}"
            );
        }
        let case = samples::paper36_case();
        let narrow = samples::explicit_gear_mesh(&case, 0, (0..3).collect());
        let (wide, body, in_block) = window_mesh();
        let narrow_body =
            ExplicitBody::new(&narrow.nodes, &narrow.elements, body.material).unwrap();
        let narrow_block: Vec<bool> = narrow.element_fine.iter().map(|f| !f).collect();
        let (three, six) = (
            of(&narrow, &narrow_body, &narrow_block),
            of(&wide, &body, &in_block),
        );
        eprintln!("paper 36: three fine teeth {three:.1} Hz, six {six:.1} Hz");
        assert!(six < three, "{six} against {three}");
    }
}
