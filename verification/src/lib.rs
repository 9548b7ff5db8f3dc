//! Verification studies of mpmice: the harness (result format, order fits,
//! plots) and the studies themselves.

pub mod harness;
pub mod mpm_studies;

/// A study: name, one-line description, runner (`quick` = coarse resolutions).
pub type Study = (
    &'static str,
    &'static str,
    fn(bool) -> anyhow::Result<harness::StudyResult>,
);

/// Every study the binary knows.
pub const STUDIES: &[Study] = &[
    (
        "mpm_bar_1d",
        "1D elastic bar, fixed-free, mode 1 vs exact; energy drift",
        mpm_studies::mpm_bar_1d,
    ),
    (
        "mpm_mms_axis_aligned",
        "Wallstedt-Guilkey axis-aligned MMS, 1D/2D, all shape functions, A = 1e-4 and 0.05",
        mpm_studies::mpm_mms_axis_aligned,
    ),
];
