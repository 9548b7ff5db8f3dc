//! Error type and solve report shared by every solver in the crate.

use thiserror::Error;

/// Result alias used throughout the crate.
pub type Result<T> = std::result::Result<T, SolverError>;

/// Everything that can go wrong in assembly, factorisation or iteration.
#[derive(Debug, Error)]
pub enum SolverError {
    /// An iterative method hit its iteration limit before reaching the
    /// requested tolerance. The solution vector holds the last iterate.
    #[error("not converged after {iterations} iterations (relative residual {rel_residual:e})")]
    NotConverged {
        /// Iterations performed.
        iterations: usize,
        /// Relative residual `||b - A x|| / ||b||` of the returned iterate.
        rel_residual: f64,
    },
    /// An iterative method broke down (division by zero, loss of positivity,
    /// non-finite numbers).
    #[error("breakdown at iteration {iteration}: {what}")]
    Breakdown {
        /// Iteration at which the breakdown was detected.
        iteration: usize,
        /// Human-readable description of the breakdown.
        what: String,
    },
    /// The matrix (or operator) is singular or not positive definite.
    #[error("singular or indefinite system: {detail}")]
    Singular {
        /// Human-readable description (pivot index, component, ...).
        detail: String,
    },
    /// A vector or matrix has the wrong size.
    #[error("dimension mismatch: expected {expected}, got {got}")]
    Dimension {
        /// Expected length / size.
        expected: usize,
        /// Length / size actually supplied.
        got: usize,
    },
    /// Input data is invalid (negative or non-finite coefficient, index out of
    /// range, changed sparsity pattern, ...).
    #[error("invalid input: {detail}")]
    InvalidInput {
        /// Human-readable description.
        detail: String,
    },
    /// The underlying factorisation library reported an error.
    #[error("factorisation failed: {0}")]
    Factorisation(String),
    /// I/O error (Matrix Market output).
    #[error("i/o error: {0}")]
    Io(#[from] std::io::Error),
}

impl SolverError {
    pub(crate) fn invalid(detail: impl Into<String>) -> Self {
        SolverError::InvalidInput {
            detail: detail.into(),
        }
    }
}

/// `x > 0` and not NaN (NaN-aware positivity test used for pivots and
/// Krylov denominators).
#[inline]
pub(crate) fn is_pos(x: f64) -> bool {
    x > 0.0
}

/// Returns `Err(Dimension)` unless `got == expected`.
pub(crate) fn check_len(expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(SolverError::Dimension { expected, got })
    }
}

/// Statistics of one solve.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SolveReport {
    /// Number of iterations (Krylov iterations, multigrid cycles); 0 for
    /// direct solves and for a zero right-hand side.
    pub iterations: usize,
    /// Final relative residual `||b - A x||_2 / ||b||_2` (true residual,
    /// recomputed from the returned solution; 0 when `b = 0`).
    pub rel_residual: f64,
    /// Wall-clock seconds of setup attributable to this solver object
    /// (factorisation, multigrid hierarchy); 0 for Krylov methods whose
    /// operator and preconditioner are built by the caller.
    pub setup_s: f64,
    /// Wall-clock seconds spent in this solve call.
    pub solve_s: f64,
}
