//! Sparse linear algebra for mpmice. Knows no physics: assembly from triplets,
//! direct factorisations, Krylov methods and preconditioners, and geometric
//! multigrid for cell-centred structured-grid operators.
//!
//! Every fallible call returns [`Result`]`<_, `[`SolverError`]`>`; every solve
//! returns a [`SolveReport`]. All algorithms run on the calling thread
//! (faer is called with `Par::Seq`).
//!
//! * [`Assembler`] / [`SparsityPattern`]: triplets → faer CSC matrix, with
//!   in-place value refresh.
//! * [`Cholesky`], [`Lu`]: sparse direct solvers with reusable symbolic
//!   analysis ([`Cholesky::refactor`]) and allocation-free solves.
//! * [`pcg`], [`bicgstab`] over any [`LinearOperator`] (e.g. [`CsrMatrix`],
//!   faer's CSC matrix, [`CellStencil`] matrix-free) with any
//!   [`Preconditioner`] ([`Identity`], [`Jacobi`], [`IncompleteCholesky`],
//!   [`Multigrid`]) and a caller-owned [`KrylovWorkspace`].
//! * [`CellStencil`] + [`Multigrid`]: variable-coefficient cell-centred
//!   operators on 2D/3D grids and their multigrid solver/preconditioner.
//! * [`write_matrix_market`]: atomic Matrix Market output.
//!
//! ```
//! use solvers::{pcg, BoundaryKind, CellStencil, KrylovOptions, KrylovWorkspace, MgOptions, Multigrid};
//!
//! # fn main() -> solvers::Result<()> {
//! // 32x32 cells, unit face coefficients, Dirichlet (ghost 0) all around.
//! let a = CellStencil::uniform([32, 32, 1], 1.0, 0.0, BoundaryKind::Dirichlet)?;
//! let mg = Multigrid::new(&a, &MgOptions::default())?;
//! let b = vec![1.0; a.num_cells()];
//! let mut x = vec![0.0; a.num_cells()];
//! let mut ws = KrylovWorkspace::new();
//! let opts = KrylovOptions { rel_tol: 1e-10, max_iter: 100 };
//! let report = pcg(&a, &mg, &b, &mut x, &opts, &mut ws)?;
//! assert!(report.rel_residual <= 1e-10 && report.iterations < 15);
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

pub mod assembly;
pub mod direct;
pub mod error;
pub mod krylov;
pub mod matrix_market;
pub mod multigrid;
pub mod operator;
pub mod precond;
pub mod stencil;

pub use assembly::{Assembler, SparsityPattern};
pub use direct::{Cholesky, Lu};
pub use error::{Result, SolveReport, SolverError};
pub use krylov::{bicgstab, pcg, KrylovOptions, KrylovWorkspace};
pub use matrix_market::write_matrix_market;
pub use multigrid::{Cycle, MgOptions, Multigrid, Prolongation};
pub use operator::{CsrMatrix, LinearOperator, Preconditioner};
pub use precond::{Identity, IncompleteCholesky, Jacobi};
pub use stencil::{BoundaryKind, CellStencil};

/// Re-export of the faer sparse matrix type used throughout the crate.
pub use faer::sparse::SparseColMat;

#[cfg(test)]
mod send_sync {
    fn assert_send_sync<T: Send + Sync>() {}

    #[test]
    fn solver_types_are_send_and_sync() {
        assert_send_sync::<crate::Multigrid>();
        assert_send_sync::<crate::Cholesky>();
        assert_send_sync::<crate::Lu>();
        assert_send_sync::<crate::CellStencil>();
        assert_send_sync::<crate::IncompleteCholesky>();
        assert_send_sync::<crate::KrylovWorkspace>();
        assert_send_sync::<crate::Assembler>();
    }
}
