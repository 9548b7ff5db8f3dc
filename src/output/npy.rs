//! NumPy `.npy` arrays (format 1.0, C order, little-endian `<f8` or
//! `<u8`): the checkpoints' array files and the `npy` snapshot format, which
//! `numpy.load` reads without any package of ours.

use std::io::{self, Write};

use npyz::WriterBuilder;

/// Starts a `.npy` array of `shape` with dtype `descr` (`"<f8"`, `"<u8"`)
/// on `w`; the caller pushes the `shape`'s product of values in C order and
/// calls `finish`.
///
/// # Errors
/// An invalid `descr`, or an error of `w`.
pub fn begin<T: npyz::Serialize, W: Write>(
    w: W,
    descr: &str,
    shape: &[usize],
) -> io::Result<npyz::NpyWriter<T, W>> {
    let shape: Vec<u64> = shape.iter().map(|&d| d as u64).collect();
    let dtype = npyz::DType::Plain(
        descr
            .parse()
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?,
    );
    npyz::WriteOptions::<T>::new()
        .dtype(dtype)
        .shape(&shape)
        .writer(w)
        .begin_nd()
}
