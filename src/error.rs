//! Typed errors of the library. The CLI reports them through `anyhow`.

use std::path::PathBuf;

/// A scene file that cannot be used: names the key path and what is allowed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("scene error at `{path}`: {message}")]
pub struct SceneError {
    /// Dotted key path, e.g. `materials[0].density`.
    pub path: String,
    /// What is wrong and which values are allowed.
    pub message: String,
}

impl SceneError {
    /// Builds an error for `path` with `message`.
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// Where in a run a numerical failure happened.
#[derive(Debug, Clone, PartialEq)]
pub struct FailureSite {
    /// Step number (0-based count of completed steps when it failed).
    pub step: u64,
    /// Simulation time at the start of the failing step.
    pub time: f64,
    /// Offending particle, if any.
    pub particle: Option<usize>,
    /// Offending grid node or cell (flat index), if any.
    pub cell: Option<usize>,
}

impl std::fmt::Display for FailureSite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "step {}, t = {:.6e}", self.step, self.time)?;
        if let Some(p) = self.particle {
            write!(f, ", particle {p}")?;
        }
        if let Some(c) = self.cell {
            write!(f, ", cell {c}")?;
        }
        Ok(())
    }
}

/// Library error.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Invalid scene.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A numerical failure (NaN, inverted particle, particle off the grid, ...).
    #[error("numerical failure at {site}: {what}")]
    Numerical {
        /// Where it happened.
        site: FailureSite,
        /// What went wrong.
        what: String,
    },
    /// A fluid (ICE) failure; names step, time, cell and material.
    #[error("fluid: {0}")]
    Fluid(#[from] crate::ice::IceError),
    /// The watchdog found a non-finite or impossible value after a step.
    #[error("watchdog: after step {step}, t = {time:.6e}: {what}")]
    Watchdog {
        /// Completed steps when it was found.
        step: u64,
        /// Simulation time when it was found.
        time: f64,
        /// The site, material, field and value.
        what: String,
    },
    /// The run would not finish: its time step collapsed, or the first one
    /// projects an absurd number of steps; names what sets it.
    #[error("no progress at step {step}, t = {time:.6e}: {what}")]
    Progress {
        /// Completed steps when it was found.
        step: u64,
        /// Simulation time when it was found.
        time: f64,
        /// The cause: Δt, the limit and the particle or cell (and
        /// material) that sets it.
        what: String,
    },
    /// The run was stopped by an interrupt (Ctrl-C) at the end of a step.
    #[error("interrupted after step {step}, t = {time:.6e}")]
    Interrupted {
        /// Completed steps.
        step: u64,
        /// Simulation time.
        time: f64,
    },
    /// A run stopped by `cause`; the last good state was saved.
    #[error("{cause}; {} saved in {}", saved_what(cause, *step, *time), checkpoint.display())]
    Stopped {
        /// Why it stopped.
        cause: Box<Error>,
        /// The checkpoint folder of the last good state.
        checkpoint: PathBuf,
        /// Its step.
        step: u64,
        /// Its time.
        time: f64,
    },
    /// A checkpoint could not be written or read.
    #[error(transparent)]
    Checkpoint(#[from] crate::output::checkpoint::CheckpointError),
    /// File output failed.
    #[error("I/O error on {path}: {source}")]
    Io {
        /// The file being written or read.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
}

/// What a stop saved: the state at the interrupt, or the last good one.
fn saved_what(cause: &Error, step: u64, time: f64) -> String {
    match cause {
        Error::Interrupted { .. } => "checkpoint".into(),
        _ => format!("last good state (step {step}, t = {time:.6e})"),
    }
}

impl Error {
    /// The time step to retry below when the failure is recoverable with a
    /// smaller step (`None`: it is not).
    pub fn retry_dt(&self) -> Option<f64> {
        match self {
            Error::Fluid(e) => e.retry_dt(),
            _ => None,
        }
    }

    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// Library result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
