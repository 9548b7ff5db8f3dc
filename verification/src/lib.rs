//! Verification studies of mpmice: the harness (result format, order fits,
//! plots) and the studies themselves.

pub mod harness;
