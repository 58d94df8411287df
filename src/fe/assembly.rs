//! Global assembly (faer sparse) and the constrained, factorized stiffness.
//!
//! DOF numbering: node i has u = 2i, v = 2i + 1. Fixed DOFs are removed (prescribed zero); the
//! reduced K is factorized once by sparse Cholesky (K = L Lᵀ, faer) and the factor is reused
//! for every right-hand side.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMat, Triplet};
use faer::{get_global_parallelism, Conj, Mat, MatMut, Par, Side};
use nalgebra::{Matrix3, Point2};
use rayon::prelude::*;
use thiserror::Error;

use super::q8;
use crate::resources::MemoryEstimate;

#[derive(Debug, Error, PartialEq)]
pub enum FeError {
    #[error("element {element} is inverted or degenerate (smallest det J = {det_j:.3e}); refine the mesh or check the geometry")]
    BadElement { element: usize, det_j: f64 },
    #[error("the stiffness matrix is not positive definite after constraints ({reason}): the body is under-constrained")]
    NotPositiveDefinite { reason: String },
    #[error("sparse matrix assembly failed: {0}")]
    Assembly(String),
    #[error(transparent)]
    TooLarge(#[from] crate::resources::TooLarge),
    /// A checkpoint that does not belong to the scene it was to resume.
    #[error("cannot resume from the checkpoint: {0}")]
    Resume(String),
    /// A run's state that could not be carried to the next window's mesh.
    #[error("{0}")]
    Remeshing(String),
    /// A body whose mesh cannot give what is asked of it (e.g. no rim under its teeth).
    #[error("{0}")]
    Body(String),
}

/// The element's node coordinates.
pub fn element_nodes(nodes: &[Point2<f64>], element: &[usize; 8]) -> [Point2<f64>; 8] {
    element.map(|i| nodes[i])
}

/// Checks every element's Jacobian at its Gauss points.
pub fn check_elements(nodes: &[Point2<f64>], elements: &[[usize; 8]]) -> Result<(), FeError> {
    for (i, e) in elements.iter().enumerate() {
        let det_j = q8::min_jacobian(&element_nodes(nodes, e));
        if !(det_j > 0.0) {
            return Err(FeError::BadElement { element: i, det_j });
        }
    }
    Ok(())
}

/// Triplets (lower triangle, row ≥ col) of the global stiffness K = Σ K_e.
pub fn stiffness_triplets(
    nodes: &[Point2<f64>],
    elements: &[[usize; 8]],
    d: &Matrix3<f64>,
    thickness: f64,
) -> Vec<(usize, usize, f64)> {
    element_triplets(nodes, elements, |xe| q8::stiffness(xe, d, thickness))
}

/// Stored lower-triangle entries of one Q8 element matrix: 16 DOFs, 16·17/2.
pub const Q8_TRIPLETS: usize = 136;

/// The memory of assembling K on a Q8 mesh of `size`, known from the counts alone (so a mesh
/// too large to build is refused before it is built) [bytes]:
/// * the mesh: two coordinates per node, eight indices and a flag per element;
/// * the triplets, 24 bytes each, with faer's 8-byte sort index;
/// * K's lower triangle in CSC, 16 bytes per entry. Two nodes share an entry block when they
///   share an element: 28 node pairs per element, less the 3 of every interior edge, which two
///   elements share; with E_int = 2F − E_b/2 and E_b = N − 3F ([`crate::mesh::mesh_size`]) that
///   is 22F + 1.5 E_b = 17.5F + 1.5N pairs of 4 entries, and 3 entries per node.
///
/// The symbolic analysis and faer's small work arrays are left out; the factor is checked on
/// its own, before it is computed ([`AssembledStiffness::factorize`]).
pub fn assembly_memory(size: crate::mesh::MeshSize) -> MemoryEstimate {
    let (nodes, elements) = (size.nodes as f64, size.elements as f64);
    let entries = 4.0 * (17.5 * elements + 1.5 * nodes) + 3.0 * nodes;
    MemoryEstimate::part("mesh", nodes * 16.0 + elements * 65.0)
        .and(MemoryEstimate::part(
            "stiffness triplets",
            elements * Q8_TRIPLETS as f64 * (24.0 + 8.0),
        ))
        .and(MemoryEstimate::part("K", entries * 16.0))
}

/// Triplets (lower triangle, row ≥ col) of Σ_e M_e for the element matrices `matrix` gives
/// (DOF order u₀, v₀, u₁, v₁, …).
pub fn element_triplets(
    nodes: &[Point2<f64>],
    elements: &[[usize; 8]],
    matrix: impl Fn(&[Point2<f64>; 8]) -> q8::ElementMatrix,
) -> Vec<(usize, usize, f64)> {
    let mut triplets = Vec::with_capacity(elements.len() * Q8_TRIPLETS);
    for e in elements {
        let k = matrix(&element_nodes(nodes, e));
        let dofs: [usize; 16] = std::array::from_fn(|a| 2 * e[a / 2] + a % 2);
        for a in 0..16 {
            for b in 0..16 {
                if dofs[a] >= dofs[b] {
                    triplets.push((dofs[a], dofs[b], k[(a, b)]));
                }
            }
        }
    }
    triplets
}

/// y = K x for a lower-triangle triplet list of a symmetric K.
pub fn symmetric_product(triplets: &[(usize, usize, f64)], x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; x.len()];
    for &(r, c, v) in triplets {
        y[r] += v * x[c];
        if r != c {
            y[c] += v * x[r];
        }
    }
    y
}

/// K with some DOFs fixed at zero, assembled, with the symbolic analysis of its Cholesky
/// factor (faer: AMD ordering, simplicial or supernodal): what the numeric factorization will
/// take is known here, before it runs.
pub struct AssembledStiffness {
    dofs: usize,
    /// Reduced index of each global DOF (None: fixed).
    free_index: Vec<Option<usize>>,
    matrix: SparseColMat<usize, f64>,
    symbolic: SymbolicCholesky<usize>,
}

impl AssembledStiffness {
    /// Removes `fixed` DOFs from the lower-triangle triplets of K, assembles the rest and
    /// analyses its factor. The triplets are taken, reduced in their own storage and freed
    /// here, so the factorization holds only K and L.
    pub fn new(
        dofs: usize,
        triplets: Vec<(usize, usize, f64)>,
        fixed: &[usize],
    ) -> Result<Self, FeError> {
        let mut is_fixed = vec![false; dofs];
        fixed.iter().for_each(|&d| is_fixed[d] = true);
        let mut free_index = vec![None; dofs];
        let mut n = 0;
        for (d, index) in free_index.iter_mut().enumerate() {
            if !is_fixed[d] {
                *index = Some(n);
                n += 1;
            }
        }
        // Same size and alignment: std's collect reuses the triplets' allocation here (an
        // optimization std does not promise; without it the reduced copy lives only until K
        // is assembled).
        let reduced: Vec<Triplet<usize, usize, f64>> = triplets
            .into_iter()
            .filter_map(|(r, c, v)| match (free_index[r], free_index[c]) {
                (Some(r), Some(c)) => Some(Triplet::new(r, c, v)),
                _ => None,
            })
            .collect();
        let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &reduced)
            .map_err(|e| FeError::Assembly(format!("{e:?}")))?;
        drop(reduced);
        let symbolic = factorize_symbolic_cholesky(
            matrix.symbolic(),
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .map_err(|e| FeError::Assembly(format!("{e:?}")))?;
        Ok(Self {
            dofs,
            free_index,
            matrix,
            symbolic,
        })
    }

    /// Unknowns after the fixed DOFs are removed.
    pub fn free_dofs(&self) -> usize {
        self.matrix.nrows()
    }

    /// What the numeric factorization adds to K: L's values and faer's workspace [bytes].
    pub fn factorization_memory(&self) -> MemoryEstimate {
        let scratch = self
            .symbolic
            .factorize_numeric_llt_scratch::<f64>(get_global_parallelism(), Default::default());
        MemoryEstimate::part("Cholesky factor", 8.0 * self.symbolic.len_val() as f64).and(
            MemoryEstimate::part("factorization workspace", scratch.size_bytes() as f64),
        )
    }

    /// Factorizes K = L Lᵀ, once [`Self::factorization_memory`] has passed the memory check
    /// ([`crate::resources`]).
    pub fn factorize(self) -> Result<FactorizedStiffness, FeError> {
        let memory = self.factorization_memory();
        crate::resources::check_memory(
            &format!(
                "the Cholesky factor of a stiffness matrix of {} unknowns",
                self.free_dofs()
            ),
            &memory,
            COARSEN,
        )?;
        let not_positive = |reason: String| FeError::NotPositiveDefinite { reason };
        let mut values = Vec::new();
        values
            .try_reserve_exact(self.symbolic.len_val())
            .map_err(|e| FeError::Assembly(format!("the factor does not fit in memory: {e}")))?;
        values.resize(self.symbolic.len_val(), 0.0);
        let par = get_global_parallelism();
        let mut scratch = MemBuffer::try_new(
            self.symbolic
                .factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|e| FeError::Assembly(format!("the workspace does not fit in memory: {e:?}")))?;
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut values,
                self.matrix.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .map_err(|e| not_positive(format!("{e:?}")))?;
        Ok(FactorizedStiffness {
            dofs: self.dofs,
            free_index: self.free_index,
            symbolic: self.symbolic,
            values,
        })
    }
}

/// What to change when a mesh or a stiffness factor is too large for the memory.
pub const COARSEN: &str =
    "coarsen the mesh (mesh.fine_element_mm, mesh.coarse_element_mm; for the \
                       explicit FE fe.explicit_fine_element_mm, fe.explicit_coarse_element_mm)";

/// K with some DOFs fixed at zero, factorized.
pub struct FactorizedStiffness {
    dofs: usize,
    /// Reduced index of each global DOF (None: fixed).
    free_index: Vec<Option<usize>>,
    symbolic: SymbolicCholesky<usize>,
    /// L's values in `symbolic`'s layout.
    values: Vec<f64>,
}

impl FactorizedStiffness {
    /// [`AssembledStiffness::new`], then [`AssembledStiffness::factorize`].
    pub fn new(
        dofs: usize,
        triplets: Vec<(usize, usize, f64)>,
        fixed: &[usize],
    ) -> Result<Self, FeError> {
        AssembledStiffness::new(dofs, triplets, fixed)?.factorize()
    }

    /// Solves K X = B in place for the reduced columns of `rhs`, with faer's global
    /// parallelism.
    fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        self.solve_in_place_with(rhs, get_global_parallelism());
    }

    /// [`Self::solve_in_place`] with parallelism `par`.
    fn solve_in_place_with(&self, rhs: MatMut<'_, f64>, par: Par) {
        let mut scratch = MemBuffer::new(
            self.symbolic
                .solve_in_place_scratch::<f64>(rhs.ncols(), par),
        );
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            par,
            MemStack::new(&mut scratch),
        );
    }

    /// Number of unknowns after constraints.
    pub fn free_dofs(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Displacements for the given load columns (global DOF order; fixed DOFs come out 0).
    pub fn solve_columns(&self, loads: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let n = self.free_dofs();
        let mut rhs = Mat::<f64>::zeros(n, loads.len());
        for (j, load) in loads.iter().enumerate() {
            for (d, index) in self.free_index.iter().enumerate() {
                if let Some(i) = index {
                    rhs[(*i, j)] = load[d];
                }
            }
        }
        self.solve_in_place(rhs.as_mut());
        (0..loads.len())
            .map(|j| {
                let mut u = vec![0.0; self.dofs];
                for (d, index) in self.free_index.iter().enumerate() {
                    if let Some(i) = index {
                        u[d] = rhs[(*i, j)];
                    }
                }
                u
            })
            .collect()
    }

    /// Condensed compliance between point loads: G[k, l] = d_kᵀ u_l at node k, where u_l solves
    /// K u = unit force at node l along d_l. Solved in blocks of columns so memory stays
    /// O(free DOFs × block × threads).
    pub fn compliance_between(&self, points: &[(usize, [f64; 2])]) -> nalgebra::DMatrix<f64> {
        self.compliance_and_influence(points, &[]).0
    }

    /// [`Self::compliance_between`], and the influence of the same unit loads on linear
    /// functionals of the displacements: S[r, l] = Σ_(dof, c) ∈ sensors[r] c · u_l[dof] (e.g. a
    /// recovered stress component, [`crate::fe::recovery`]), from the same solves.
    pub fn compliance_and_influence(
        &self,
        points: &[(usize, [f64; 2])],
        sensors: &[Vec<(usize, f64)>],
    ) -> (nalgebra::DMatrix<f64>, nalgebra::DMatrix<f64>) {
        const BLOCK: usize = 64;
        let n = self.free_dofs();
        let m = points.len();
        let reduced = |node: usize, axis: usize| self.free_index[2 * node + axis];
        let mut g = nalgebra::DMatrix::<f64>::zeros(m, m);
        let rows = sensors.len();
        let mut influence = nalgebra::DMatrix::<f64>::zeros(rows, m);
        if m == 0 {
            return (g, influence);
        }
        // The sensors on the reduced unknowns (a fixed DOF is zero).
        let sensors: Vec<Vec<(usize, f64)>> = sensors
            .iter()
            .map(|row| {
                row.iter()
                    .filter_map(|(dof, c)| self.free_index[*dof].map(|i| (i, *c)))
                    .collect()
            })
            .collect();
        // The blocks side by side, each solved on one thread and written into its own columns
        // of G and S (column-major): a block's supernodal solve is too narrow for faer's own
        // threads to pay (they mostly wait), whole blocks are not.
        let influence_blocks: Vec<&mut [f64]> = if rows > 0 {
            influence.as_mut_slice().chunks_mut(rows * BLOCK).collect()
        } else {
            Vec::new()
        };
        let mut influence_blocks: Vec<Option<&mut [f64]>> =
            influence_blocks.into_iter().map(Some).collect();
        influence_blocks.resize_with(m.div_ceil(BLOCK), || None);
        g.as_mut_slice()
            .par_chunks_mut(m * BLOCK)
            .zip(influence_blocks.into_par_iter())
            .enumerate()
            .for_each(|(b, (columns, sensed))| {
                let start = b * BLOCK;
                let width = columns.len() / m;
                let mut rhs = Mat::<f64>::zeros(n, width);
                for (j, (node, d)) in points[start..start + width].iter().enumerate() {
                    for (axis, component) in d.iter().enumerate() {
                        if let Some(i) = reduced(*node, axis) {
                            rhs[(i, j)] = *component;
                        }
                    }
                }
                self.solve_in_place_with(rhs.as_mut(), Par::Seq);
                for j in 0..width {
                    for (k, (node, d)) in points.iter().enumerate() {
                        let mut value = 0.0;
                        for (axis, component) in d.iter().enumerate() {
                            if let Some(i) = reduced(*node, axis) {
                                value += component * rhs[(i, j)];
                            }
                        }
                        columns[j * m + k] = value;
                    }
                }
                if let Some(sensed) = sensed {
                    for j in 0..width {
                        for (r, row) in sensors.iter().enumerate() {
                            sensed[j * rows + r] = row.iter().map(|(i, c)| c * rhs[(*i, j)]).sum();
                        }
                    }
                }
            });
        (g, influence)
    }

    pub fn solve(&self, load: &[f64]) -> Vec<f64> {
        self.solve_columns(std::slice::from_ref(&load.to_vec()))
            .pop()
            .expect("one column")
    }
}
