//! The integration tests, one module a file, in one test crate (see
//! `autotests` in Cargo.toml). Run one file's tests with its module path,
//! e.g. `cargo test --release --test integration reaction::`.

mod axisymmetric;
mod cases_3d_and_semi_implicit;
mod cli_overrides;
mod conservation;
mod conservation_account;
mod contact;
mod coupled;
mod coupled_implicit;
mod determinism;
mod failure;
mod formulations;
mod guards;
mod impm_column;
mod impm_cylinder;
mod impm_mms;
mod impm_prescribed;
mod inflow;
mod interrupt;
mod lian_contact;
mod lian_membrane;
mod memory;
mod mie_gruneisen;
mod mpm_3d;
mod mpm_bar;
mod mpm_mms;
mod multiphase;
mod multiphase_hard;
mod multiphase_rz;
mod npy_snapshots;
mod plasticity;
mod reaction;
mod restart;
mod scene_errors;
mod scene_fuzz;
mod scene_modes;
mod sod;
mod taylor_anvil;
mod two_solids_in_air;
mod water_air;
mod york_airbag;
mod york_gas;
mod york_membrane;
