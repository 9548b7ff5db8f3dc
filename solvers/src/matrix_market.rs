//! Matrix Market output.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use faer::sparse::SparseColMat;

use crate::error::Result;

/// Writes `a` as a Matrix Market `coordinate real general` file (1-based
/// indices, all stored entries, values with 17 significant digits).
///
/// The file is written to `path` with `.tmp` appended and then renamed over
/// `path`, so readers never see a partial file.
pub fn write_matrix_market(path: impl AsRef<Path>, a: &SparseColMat<usize, f64>) -> Result<()> {
    let path = path.as_ref();
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = std::path::PathBuf::from(tmp);
    let result = (|| -> Result<()> {
        let mut w = BufWriter::new(File::create(&tmp)?);
        let (sym, val) = a.parts();
        let nnz: usize = (0..sym.ncols()).map(|j| sym.col_range(j).len()).sum();
        writeln!(w, "%%MatrixMarket matrix coordinate real general")?;
        writeln!(w, "% written by the mpmice solvers crate")?;
        writeln!(w, "{} {} {}", sym.nrows(), sym.ncols(), nnz)?;
        for j in 0..sym.ncols() {
            for k in sym.col_range(j) {
                writeln!(w, "{} {} {:.16e}", sym.row_idx()[k] + 1, j + 1, val[k])?;
            }
        }
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        Ok(())
    })();
    match result {
        Ok(()) => {
            std::fs::rename(&tmp, path)?;
            Ok(())
        }
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}
