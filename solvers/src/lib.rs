//! Sparse linear algebra for mpmice. Knows no physics: assembly from triplets,
//! direct factorisations, Krylov methods and preconditioners, and geometric
//! multigrid for cell-centred structured-grid operators.
//!
//! Every fallible call returns [`Result`]`<_, `[`SolverError`]`>`; every solve
//! returns a [`SolveReport`]. All algorithms run on the calling thread.

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
