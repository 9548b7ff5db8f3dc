//! ParaView VTK XML writers (the zlib compression by `flate2`).
//!
//! * [`write_vtu_points`]: particles as an `UnstructuredGrid` of `VTK_VERTEX`
//!   cells (one per point), so ParaView shows them without a glyph filter.
//! * [`write_vtu_quads`]: a quadrilateral surface mesh (membrane elements)
//!   as an `UnstructuredGrid` of `VTK_QUAD` cells.
//! * [`write_vti`]: a uniform grid as `ImageData` with point and cell data.
//! * [`PvdSeries`]: a `.pvd` collection listing the files of a time series.
//!
//! Data arrays are stored as `format="appended"` with `encoding="raw"`,
//! `header_type="UInt64"` and `byte_order="LittleEndian"`: after the XML
//! header comes `<AppendedData encoding="raw">`, an underscore, then for
//! each array a little-endian `u64` byte count followed by the raw
//! little-endian values. Each `DataArray`'s `offset` attribute is the byte
//! position of its count, measured from just after the underscore. All
//! floating-point data is `Float64`.
//!
//! With [`Compression::Zlib`] the file names `compressor=
//! "vtkZLibDataCompressor"` and each array is cut into blocks of
//! [`ZLIB_BLOCK`] bytes (VTK's own block size) compressed one by one: its
//! header is `u64` values, the number of blocks, the block size, the size of
//! a partial last block (0 when the last block is full) and the compressed
//! size of every block, then come the compressed blocks. Blocks are
//! compressed in parallel a batch at a time and written as they are done,
//! so the writer holds one batch, never a whole array; the header and the
//! `offset` attributes, which depend on the compressed sizes, are written
//! as zero placeholders of fixed width and filled in once the sizes are
//! known (an offset is written as 20 digits with leading zeros).
//!
//! All files are written with [`atomic_write`], so a reader never sees a
//! half-written file.

use std::collections::HashSet;
use std::fmt::Write as _;
use std::fs::File;
use std::io::{self, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::{atomic_write, fmt_f64};

/// VTK cell type id of a single-point cell.
const VTK_VERTEX: u8 = 1;

/// VTK cell type id of a four-node quadrilateral.
const VTK_QUAD: u8 = 9;

/// Bytes of uncompressed data in one zlib block (VTK's default, 32 KiB).
pub const ZLIB_BLOCK: usize = 32 * 1024;

/// Blocks compressed together (in parallel) before they are written: 2 MiB
/// of uncompressed data held at a time.
const ZLIB_BATCH: usize = 64;

/// Width of an `offset` attribute of a compressed file (`u64::MAX` has 20
/// digits), written with leading zeros.
const OFFSET_DIGITS: usize = 20;

/// How the arrays of the appended-data section are stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Compression {
    /// Raw little-endian values (each array behind its `u64` byte count).
    #[default]
    None,
    /// zlib blocks (`vtkZLibDataCompressor`) at `level` 1 (fastest) to 9
    /// (smallest).
    Zlib {
        /// zlib level, 1–9.
        level: u32,
    },
}

/// The values of one named field, one tuple per point or per cell.
#[derive(Clone, Copy)]
pub enum FieldData<'a> {
    /// One `f64` per entity (`NumberOfComponents="1"`).
    Scalar(&'a [f64]),
    /// Three components per entity (`NumberOfComponents="3"`).
    Vector(&'a [[f64; 3]]),
    /// Nine components per entity, row-major
    /// (`[xx, xy, xz, yx, yy, yz, zx, zy, zz]`, `NumberOfComponents="9"`).
    Tensor(&'a [[f64; 9]]),
    /// `n` tuples of `components` (1, 3 or 9) values computed as they are
    /// written: `f(i, out)` writes tuple `i` into `out[..components]`.
    Computed {
        /// Number of tuples.
        n: usize,
        /// Values per tuple.
        components: usize,
        /// Writes one tuple.
        f: &'a (dyn Fn(usize, &mut [f64]) + Sync),
    },
}

impl std::fmt::Debug for FieldData<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "FieldData({} tuples of {})",
            self.len(),
            self.components()
        )
    }
}

impl FieldData<'_> {
    /// Number of tuples (entities), not of scalar values.
    pub fn len(&self) -> usize {
        match self {
            FieldData::Scalar(d) => d.len(),
            FieldData::Vector(d) => d.len(),
            FieldData::Tensor(d) => d.len(),
            FieldData::Computed { n, .. } => *n,
        }
    }

    /// `true` when there are no tuples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of components per tuple (1, 3 or 9).
    pub fn components(&self) -> usize {
        match self {
            FieldData::Scalar(_) => 1,
            FieldData::Vector(_) => 3,
            FieldData::Tensor(_) => 9,
            FieldData::Computed { components, .. } => *components,
        }
    }
}

/// A named field to write as a VTK `DataArray`.
#[derive(Clone, Copy, Debug)]
pub struct Field<'a> {
    /// Array name shown in ParaView (must be non-empty, without control
    /// characters, and unique within its point-data or cell-data list).
    pub name: &'a str,
    /// The values.
    pub data: FieldData<'a>,
}

impl<'a> Field<'a> {
    /// A scalar field.
    pub fn scalar(name: &'a str, data: &'a [f64]) -> Self {
        Field {
            name,
            data: FieldData::Scalar(data),
        }
    }

    /// A 3-component vector field.
    pub fn vector(name: &'a str, data: &'a [[f64; 3]]) -> Self {
        Field {
            name,
            data: FieldData::Vector(data),
        }
    }

    /// A 9-component (row-major 3×3) tensor field.
    pub fn tensor(name: &'a str, data: &'a [[f64; 9]]) -> Self {
        Field {
            name,
            data: FieldData::Tensor(data),
        }
    }
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// Checks names and lengths of a field list (`what` is "point" or "cell").
fn check_fields(what: &str, fields: &[Field], expected: usize) -> io::Result<()> {
    let mut seen = HashSet::new();
    for f in fields {
        if f.name.is_empty() {
            return Err(invalid(format!("{what} field with an empty name")));
        }
        if f.name.chars().any(char::is_control) {
            return Err(invalid(format!(
                "{what} field name {:?} contains control characters",
                f.name
            )));
        }
        if !seen.insert(f.name) {
            return Err(invalid(format!(
                "duplicate {what} field name \"{}\"",
                f.name
            )));
        }
        if f.data.len() != expected {
            return Err(invalid(format!(
                "{what} field \"{}\" has {} tuples, expected {expected}",
                f.name,
                f.data.len()
            )));
        }
    }
    Ok(())
}

/// Escapes a string for use inside a double-quoted XML attribute.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

/// One array of the appended-data section.
enum Block<'a> {
    Field(FieldData<'a>),
    Points(&'a [[f64; 3]]),
    /// `Int64` values `start, start + 1, …` (`n` of them).
    Iota {
        n: usize,
        start: i64,
    },
    /// Quadrilateral connectivity as `Int64`, four ids a cell.
    Quads(&'a [[u32; 4]]),
    /// `Int64` offsets `4, 8, …` of `n` quadrilaterals.
    QuadOffsets(usize),
    /// `n` copies of one `UInt8`.
    ConstU8 {
        n: usize,
        value: u8,
    },
}

impl Block<'_> {
    fn byte_len(&self) -> io::Result<u64> {
        let (n, size) = match self {
            Block::Field(d) => (d.len(), 8 * d.components()),
            Block::Points(p) => (p.len(), 24),
            Block::Iota { n, .. } => (*n, 8),
            Block::Quads(q) => (q.len(), 32),
            Block::QuadOffsets(n) => (*n, 8),
            Block::ConstU8 { n, .. } => (*n, 1),
        };
        (n as u64)
            .checked_mul(size as u64)
            .ok_or_else(|| invalid("data array too large".to_string()))
    }

    /// Writes the values (without the byte count in front).
    fn write_values(&self, w: &mut impl Write) -> io::Result<()> {
        match self {
            Block::Field(FieldData::Scalar(d)) => write_f64s(w, d.iter().copied()),
            Block::Field(FieldData::Vector(d)) => write_f64s(w, d.iter().flatten().copied()),
            Block::Field(FieldData::Tensor(d)) => write_f64s(w, d.iter().flatten().copied()),
            Block::Field(FieldData::Computed { n, components, f }) => {
                let mut t = [0.0; 9];
                for i in 0..*n {
                    f(i, &mut t);
                    write_f64s(w, t[..*components].iter().copied())?;
                }
                Ok(())
            }
            Block::Points(p) => write_f64s(w, p.iter().flatten().copied()),
            Block::Iota { n, start } => {
                for i in 0..*n {
                    // Indices fit in i64 for any slice that fits in memory.
                    w.write_all(&(start + i as i64).to_le_bytes())?;
                }
                Ok(())
            }
            Block::Quads(q) => {
                for id in q.iter().flatten() {
                    w.write_all(&i64::from(*id).to_le_bytes())?;
                }
                Ok(())
            }
            Block::QuadOffsets(n) => {
                for i in 1..=*n {
                    w.write_all(&(4 * i as i64).to_le_bytes())?;
                }
                Ok(())
            }
            Block::ConstU8 { n, value } => {
                let chunk = [*value; 4096];
                let mut left = *n;
                while left > 0 {
                    let k = left.min(chunk.len());
                    w.write_all(&chunk[..k])?;
                    left -= k;
                }
                Ok(())
            }
        }
    }
}

fn write_f64s(w: &mut impl Write, values: impl Iterator<Item = f64>) -> io::Result<()> {
    for v in values {
        w.write_all(&v.to_le_bytes())?;
    }
    Ok(())
}

/// Builder for the XML header and the list of appended arrays.
struct Doc<'a> {
    xml: String,
    blocks: Vec<Block<'a>>,
    /// Offset of the next raw array.
    offset: u64,
    compression: Compression,
    /// Compressed: the byte positions in `xml` of the `offset` placeholders,
    /// one per array.
    placeholders: Vec<usize>,
}

impl<'a> Doc<'a> {
    fn new(kind: &str, compression: Compression) -> Self {
        let mut xml = String::new();
        xml.push_str("<?xml version=\"1.0\"?>\n");
        let compressor = match compression {
            Compression::None => "",
            Compression::Zlib { .. } => " compressor=\"vtkZLibDataCompressor\"",
        };
        let _ = writeln!(
            xml,
            "<VTKFile type=\"{kind}\" version=\"1.0\" byte_order=\"LittleEndian\" \
             header_type=\"UInt64\"{compressor}>"
        );
        Doc {
            xml,
            blocks: Vec::new(),
            offset: 0,
            compression,
            placeholders: Vec::new(),
        }
    }

    fn line(&mut self, indent: usize, text: &str) {
        for _ in 0..indent {
            self.xml.push_str("  ");
        }
        self.xml.push_str(text);
        self.xml.push('\n');
    }

    /// Adds a `<DataArray .../>` element referring to a new appended block.
    fn array(
        &mut self,
        indent: usize,
        vtk_type: &str,
        name: &str,
        components: usize,
        block: Block<'a>,
    ) -> io::Result<()> {
        let len = block.byte_len()?;
        let offset = match self.compression {
            Compression::None => self.offset.to_string(),
            Compression::Zlib { .. } => "0".repeat(OFFSET_DIGITS),
        };
        let tag = format!(
            "<DataArray type=\"{vtk_type}\" Name=\"{}\" NumberOfComponents=\"{components}\" \
             format=\"appended\" offset=\"{offset}\"/>",
            xml_escape(name),
        );
        if let Compression::Zlib { .. } = self.compression {
            // The offset is the tag's last attribute: `"/>` follows it.
            let at = self.xml.len() + 2 * indent + tag.len() - 3 - OFFSET_DIGITS;
            self.placeholders.push(at);
        }
        self.line(indent, &tag);
        self.offset = self
            .offset
            .checked_add(8 + len)
            .ok_or_else(|| invalid("appended data too large".to_string()))?;
        self.blocks.push(block);
        Ok(())
    }

    /// Adds a `<PointData>`/`<CellData>` section with the given fields.
    fn fields(&mut self, indent: usize, section: &str, fields: &[Field<'a>]) -> io::Result<()> {
        if fields.is_empty() {
            self.line(indent, &format!("<{section}/>"));
            return Ok(());
        }
        self.line(indent, &format!("<{section}>"));
        for f in fields {
            self.array(
                indent + 1,
                "Float64",
                f.name,
                f.data.components(),
                Block::Field(f.data),
            )?;
        }
        self.line(indent, &format!("</{section}>"));
        Ok(())
    }

    /// Writes the document atomically: XML header, appended data, footer
    /// (and, compressed, the offsets filled in last).
    fn write(self, path: &Path) -> io::Result<()> {
        atomic_write(path, |w: &mut BufWriter<File>| {
            w.write_all(self.xml.as_bytes())?;
            let head: &[u8] = b"  <AppendedData encoding=\"raw\">\n   _";
            w.write_all(head)?;
            let level = match self.compression {
                Compression::None => {
                    for b in &self.blocks {
                        w.write_all(&b.byte_len()?.to_le_bytes())?;
                        b.write_values(w)?;
                    }
                    return w.write_all(FOOTER);
                }
                Compression::Zlib { level } if (1..=9).contains(&level) => level,
                Compression::Zlib { level } => {
                    return Err(invalid(format!("zlib level {level} is not 1 to 9")));
                }
            };
            let base = (self.xml.len() + head.len()) as u64;
            let mut z = ZlibBlocks::new(level);
            let mut offsets = Vec::with_capacity(self.blocks.len());
            let mut pos = base;
            for b in &self.blocks {
                offsets.push(pos - base);
                pos += z.write_array(w, pos, b)?;
            }
            w.write_all(FOOTER)?;
            for (&at, off) in self.placeholders.iter().zip(offsets) {
                w.seek(SeekFrom::Start(at as u64))?;
                write!(w, "{off:0width$}", width = OFFSET_DIGITS)?;
            }
            Ok(())
        })
    }
}

/// The end of every file.
const FOOTER: &[u8] = b"\n  </AppendedData>\n</VTKFile>\n";

/// The zlib writer of one file's arrays: a batch of raw bytes, compressed
/// block by block in parallel, and the compressed blocks' buffers, reused
/// from array to array.
struct ZlibBlocks {
    level: flate2::Compression,
    raw: Vec<u8>,
    packed: Vec<Vec<u8>>,
    /// Compressed sizes of the array's blocks so far.
    sizes: Vec<u64>,
}

impl ZlibBlocks {
    fn new(level: u32) -> Self {
        Self {
            level: flate2::Compression::new(level),
            raw: Vec::with_capacity(ZLIB_BLOCK * ZLIB_BATCH),
            packed: vec![Vec::new(); ZLIB_BATCH],
            sizes: Vec::new(),
        }
    }

    /// Writes array `b` at file position `pos` (where `w` stands): a
    /// placeholder header, the compressed blocks, then the header filled in.
    /// Returns the bytes written.
    fn write_array<W: Write + Seek>(&mut self, w: &mut W, pos: u64, b: &Block) -> io::Result<u64> {
        let len = b.byte_len()?;
        let blocks = len.div_ceil(ZLIB_BLOCK as u64);
        let header_len = 8 * (3 + blocks);
        io::copy(&mut io::repeat(0).take(header_len), w)?;
        self.sizes.clear();
        let mut sink = BatchSink { z: self, w };
        b.write_values(&mut sink)?;
        sink.flush_batch()?;
        let mut header = Vec::with_capacity(3 + self.sizes.len());
        header.extend([blocks, ZLIB_BLOCK as u64, len % ZLIB_BLOCK as u64]);
        header.extend(&self.sizes);
        if header.len() as u64 != 3 + blocks {
            return Err(io::Error::other("zlib blocks miscounted"));
        }
        w.seek(SeekFrom::Start(pos))?;
        for v in &header {
            w.write_all(&v.to_le_bytes())?;
        }
        w.seek(SeekFrom::End(0))?;
        Ok(header_len + self.sizes.iter().sum::<u64>())
    }
}

/// A [`Write`] that gathers an array's raw bytes into batches of blocks and
/// writes each batch compressed.
struct BatchSink<'z, 'w, W> {
    z: &'z mut ZlibBlocks,
    w: &'w mut W,
}

impl<W: Write> BatchSink<'_, '_, W> {
    /// Compresses the gathered blocks (in parallel) and writes them.
    fn flush_batch(&mut self) -> io::Result<()> {
        let z = &mut *self.z;
        if z.raw.is_empty() {
            return Ok(());
        }
        let level = z.level;
        let n = z.raw.len().div_ceil(ZLIB_BLOCK);
        z.raw
            .par_chunks(ZLIB_BLOCK)
            .zip(z.packed[..n].par_iter_mut())
            .try_for_each(|(raw, out)| -> io::Result<()> {
                out.clear();
                let mut e = flate2::write::ZlibEncoder::new(std::mem::take(out), level);
                e.write_all(raw)?;
                *out = e.finish()?;
                Ok(())
            })?;
        for out in &z.packed[..n] {
            self.w.write_all(out)?;
            z.sizes.push(out.len() as u64);
        }
        z.raw.clear();
        Ok(())
    }
}

impl<W: Write> Write for BatchSink<'_, '_, W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let room = ZLIB_BLOCK * ZLIB_BATCH - self.z.raw.len();
        let k = buf.len().min(room);
        self.z.raw.extend_from_slice(&buf[..k]);
        if self.z.raw.len() == ZLIB_BLOCK * ZLIB_BATCH {
            self.flush_batch()?;
        }
        Ok(k)
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// Writes particles as a VTK XML `UnstructuredGrid` (`.vtu`) made of one
/// `VTK_VERTEX` cell per point, with the given point data, its arrays stored
/// as `compression` says.
///
/// Zero points is allowed and gives a valid, empty file. Connectivity and
/// offsets are `Int64`, cell types `UInt8`.
///
/// # Errors
/// [`io::ErrorKind::InvalidInput`] (naming the field) when a field's length
/// differs from `points.len()`, a name is empty, duplicated or contains
/// control characters; otherwise any I/O error of the write.
pub fn write_vtu_points(
    path: &Path,
    points: &[[f64; 3]],
    point_data: &[Field],
    compression: Compression,
) -> io::Result<()> {
    write_vtu_point_data(path, FieldData::Vector(points), point_data, compression)
}

/// [`write_vtu_points`] with the positions given as 3-component field data
/// (e.g. computed as they are written).
///
/// # Errors
/// As [`write_vtu_points`]; also [`io::ErrorKind::InvalidInput`] when
/// `points` has other than 3 components.
pub fn write_vtu_point_data(
    path: &Path,
    points: FieldData<'_>,
    point_data: &[Field],
    compression: Compression,
) -> io::Result<()> {
    if points.components() != 3 {
        return Err(invalid(format!(
            "points have {} components, not 3",
            points.components()
        )));
    }
    let n = points.len();
    check_fields("point", point_data, n)?;
    let mut doc = Doc::new("UnstructuredGrid", compression);
    doc.line(1, "<UnstructuredGrid>");
    doc.line(
        2,
        &format!("<Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">"),
    );
    doc.fields(3, "PointData", point_data)?;
    doc.line(3, "<CellData/>");
    doc.line(3, "<Points>");
    doc.array(4, "Float64", "Points", 3, Block::Field(points))?;
    doc.line(3, "</Points>");
    doc.line(3, "<Cells>");
    doc.array(4, "Int64", "connectivity", 1, Block::Iota { n, start: 0 })?;
    doc.array(4, "Int64", "offsets", 1, Block::Iota { n, start: 1 })?;
    doc.array(
        4,
        "UInt8",
        "types",
        1,
        Block::ConstU8 {
            n,
            value: VTK_VERTEX,
        },
    )?;
    doc.line(3, "</Cells>");
    doc.line(2, "</Piece>");
    doc.line(1, "</UnstructuredGrid>");
    doc.write(path)
}

/// Writes a quadrilateral surface mesh as a VTK XML `UnstructuredGrid`
/// (`.vtu`) of `VTK_QUAD` cells with point data (one tuple per point) and
/// cell data (one per quad).
///
/// # Errors
/// [`io::ErrorKind::InvalidInput`] when a field has the wrong length or an
/// invalid/duplicate name, or a quad names a point that does not exist;
/// otherwise any I/O error of the write.
pub fn write_vtu_quads(
    path: &Path,
    points: &[[f64; 3]],
    quads: &[[u32; 4]],
    point_data: &[Field],
    cell_data: &[Field],
    compression: Compression,
) -> io::Result<()> {
    let (n, nc) = (points.len(), quads.len());
    check_fields("point", point_data, n)?;
    check_fields("cell", cell_data, nc)?;
    if let Some(q) = quads.iter().find(|q| q.iter().any(|&i| i as usize >= n)) {
        return Err(invalid(format!("quad {q:?} names a point beyond {n}")));
    }
    let mut doc = Doc::new("UnstructuredGrid", compression);
    doc.line(1, "<UnstructuredGrid>");
    doc.line(
        2,
        &format!("<Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{nc}\">"),
    );
    doc.fields(3, "PointData", point_data)?;
    doc.fields(3, "CellData", cell_data)?;
    doc.line(3, "<Points>");
    doc.array(4, "Float64", "Points", 3, Block::Points(points))?;
    doc.line(3, "</Points>");
    doc.line(3, "<Cells>");
    doc.array(4, "Int64", "connectivity", 1, Block::Quads(quads))?;
    doc.array(4, "Int64", "offsets", 1, Block::QuadOffsets(nc))?;
    doc.array(
        4,
        "UInt8",
        "types",
        1,
        Block::ConstU8 {
            n: nc,
            value: VTK_QUAD,
        },
    )?;
    doc.line(3, "</Cells>");
    doc.line(2, "</Piece>");
    doc.line(1, "</UnstructuredGrid>");
    doc.write(path)
}

/// Writes a uniform grid as a VTK XML `ImageData` (`.vti`).
///
/// The whole extent is `0 cells[0] 0 cells[1] 0 cells[2]`; use 0 for unused
/// dimensions (a 2D grid of `nx × ny` cells gives `"0 nx 0 ny 0 0"`).
/// `point_data` fields hold `(nx+1)(ny+1)(nz+1)` tuples and `cell_data`
/// fields `max(nx,1)·max(ny,1)·max(nz,1)` tuples, both ordered with x
/// fastest, then y, then z.
///
/// # Errors
/// [`io::ErrorKind::InvalidInput`] (naming the field) when a field has the
/// wrong length or an invalid/duplicate name, when `origin` or `spacing` is
/// not finite, or when the sizes overflow; otherwise any I/O error.
pub fn write_vti(
    path: &Path,
    origin: [f64; 3],
    spacing: [f64; 3],
    cells: [usize; 3],
    point_data: &[Field],
    cell_data: &[Field],
    compression: Compression,
) -> io::Result<()> {
    if origin.iter().chain(spacing.iter()).any(|v| !v.is_finite()) {
        return Err(invalid(format!(
            "non-finite origin {origin:?} or spacing {spacing:?}"
        )));
    }
    let overflow = || invalid(format!("grid of {cells:?} cells is too large"));
    let n_points = cells.iter().try_fold(1usize, |acc, &c| {
        c.checked_add(1)
            .and_then(|c1| acc.checked_mul(c1))
            .ok_or_else(overflow)
    })?;
    let n_cells = cells.iter().try_fold(1usize, |acc, &c| {
        acc.checked_mul(c.max(1)).ok_or_else(overflow)
    })?;
    check_fields("point", point_data, n_points)?;
    check_fields("cell", cell_data, n_cells)?;

    let extent = format!("0 {} 0 {} 0 {}", cells[0], cells[1], cells[2]);
    let triple = |v: [f64; 3]| format!("{} {} {}", fmt_f64(v[0]), fmt_f64(v[1]), fmt_f64(v[2]));
    let mut doc = Doc::new("ImageData", compression);
    doc.line(
        1,
        &format!(
            "<ImageData WholeExtent=\"{extent}\" Origin=\"{}\" Spacing=\"{}\">",
            triple(origin),
            triple(spacing)
        ),
    );
    doc.line(2, &format!("<Piece Extent=\"{extent}\">"));
    doc.fields(3, "PointData", point_data)?;
    doc.fields(3, "CellData", cell_data)?;
    doc.line(2, "</Piece>");
    doc.line(1, "</ImageData>");
    doc.write(path)
}

/// One entry of a [`PvdSeries`].
#[derive(Clone, Debug, PartialEq)]
pub struct PvdEntry {
    /// Simulation time of the data set.
    pub time: f64,
    /// File name of the data set, relative to the `.pvd` file's directory.
    pub file: String,
}

/// A ParaView collection file (`.pvd`) listing a time series of data sets.
///
/// Every [`push`](Self::push) rewrites the whole file atomically, so an
/// interrupted run still leaves a valid series of the steps written so far.
/// A run with several series (e.g. particles and grid) uses one
/// `PvdSeries` per series. The file is first created by the first `push`
/// (or an explicit [`write`](Self::write)).
#[derive(Clone, Debug)]
pub struct PvdSeries {
    path: PathBuf,
    entries: Vec<PvdEntry>,
}

impl PvdSeries {
    /// A new, empty series to be written at `path` (nothing is written yet).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        PvdSeries {
            path: path.into(),
            entries: Vec::new(),
        }
    }

    /// The `.pvd` file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The entries pushed so far, in push order.
    pub fn entries(&self) -> &[PvdEntry] {
        &self.entries
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// `true` when no entry has been pushed.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Appends a data set at `time` (file name relative to the `.pvd`'s
    /// directory) and rewrites the `.pvd` atomically.
    ///
    /// # Errors
    /// [`io::ErrorKind::InvalidInput`] for a non-finite time or an empty file
    /// name or one with control characters; any I/O error of the rewrite. On
    /// error the entry is not kept.
    pub fn push(&mut self, time: f64, relative_file_name: &str) -> io::Result<()> {
        if !time.is_finite() {
            return Err(invalid(format!("non-finite PVD time step {time}")));
        }
        if relative_file_name.is_empty() || relative_file_name.chars().any(char::is_control) {
            return Err(invalid(format!(
                "invalid PVD file name {relative_file_name:?}"
            )));
        }
        self.entries.push(PvdEntry {
            time,
            file: relative_file_name.to_string(),
        });
        let result = self.write();
        if result.is_err() {
            self.entries.pop();
        }
        result
    }

    /// Writes the `.pvd` file atomically with the current entries.
    ///
    /// # Errors
    /// Any I/O error of the write.
    pub fn write(&self) -> io::Result<()> {
        let mut xml = String::new();
        xml.push_str("<?xml version=\"1.0\"?>\n");
        xml.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
        xml.push_str("  <Collection>\n");
        for e in &self.entries {
            let _ = writeln!(
                xml,
                "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>",
                fmt_f64(e.time),
                xml_escape(&e.file)
            );
        }
        xml.push_str("  </Collection>\n");
        xml.push_str("</VTKFile>\n");
        atomic_write(&self.path, |w| w.write_all(xml.as_bytes()))
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_dir;
    use super::*;
    use std::fs;

    /// Value of attribute `key` in the tag text `tag` (still XML-escaped).
    fn attr<'t>(tag: &'t str, key: &str) -> Option<&'t str> {
        let pat = format!(" {key}=\"");
        let start = tag.find(&pat)? + pat.len();
        let end = start + tag[start..].find('"')?;
        Some(&tag[start..end])
    }

    /// Tiny well-formedness check: every tag is closed by `>`, quotes are
    /// balanced inside tags, and open/close tags nest properly.
    fn assert_balanced(xml: &str) {
        let mut stack: Vec<String> = Vec::new();
        let mut rest = xml;
        while let Some(i) = rest.find('<') {
            let j = rest[i..].find('>').expect("unterminated tag") + i;
            let tag = &rest[i + 1..j];
            assert_eq!(tag.matches('"').count() % 2, 0, "unbalanced quotes: {tag}");
            if tag.starts_with('?') {
                // processing instruction
            } else if let Some(name) = tag.strip_prefix('/') {
                let open = stack.pop().expect("close without open");
                assert_eq!(open, name.trim(), "mismatched close tag");
            } else if !tag.ends_with('/') {
                let name = tag.split_whitespace().next().expect("tag name");
                stack.push(name.to_string());
            }
            rest = &rest[j + 1..];
        }
        assert!(stack.is_empty(), "unclosed tags: {stack:?}");
    }

    /// A parsed appended VTK file, raw or zlib-compressed.
    struct Vtk {
        /// XML header + footer (without the binary section).
        xml: String,
        /// DataArray tags, in order.
        arrays: Vec<String>,
        /// Each array's values (decompressed), in order.
        payloads: Vec<Vec<u8>>,
        /// Each array's bytes in the file (compressed: header and blocks).
        stored: Vec<usize>,
    }

    fn u64_at(raw: &[u8], at: usize) -> u64 {
        u64::from_le_bytes(raw[at..at + 8].try_into().expect("8"))
    }

    /// Decodes the zlib array at `off` (its header, then the blocks, each
    /// checked against the sizes the header gives); returns the values and
    /// the bytes it takes in the file.
    fn unzip(raw: &[u8], off: usize) -> (Vec<u8>, usize) {
        let blocks = u64_at(raw, off) as usize;
        let block = u64_at(raw, off + 8) as usize;
        let last = u64_at(raw, off + 16) as usize;
        assert_eq!(block, ZLIB_BLOCK);
        let mut at = off + 8 * (3 + blocks);
        let mut out = Vec::new();
        for b in 0..blocks {
            let size = u64_at(raw, off + 8 * (3 + b)) as usize;
            let mut plain = Vec::new();
            flate2::read::ZlibDecoder::new(&raw[at..at + size])
                .read_to_end(&mut plain)
                .expect("zlib block");
            let expect = if b + 1 == blocks && last != 0 {
                last
            } else {
                block
            };
            assert_eq!(plain.len(), expect, "block {b} of {blocks}");
            out.extend(plain);
            at += size;
        }
        (out, at - off)
    }

    impl Vtk {
        fn read(path: &Path) -> Vtk {
            let bytes = fs::read(path).expect("read vtk");
            let marker = b"<AppendedData encoding=\"raw\">";
            let m = bytes
                .windows(marker.len())
                .position(|w| w == marker)
                .expect("AppendedData");
            let us = m + bytes[m..].iter().position(|&b| b == b'_').expect("_");
            let header = String::from_utf8(bytes[..us].to_vec()).expect("utf8 header");
            assert!(header.contains("header_type=\"UInt64\""));
            assert!(header.contains("byte_order=\"LittleEndian\""));
            let zlib = header.contains("compressor=\"vtkZLibDataCompressor\"");
            let raw = &bytes[us + 1..];
            let arrays: Vec<String> = header
                .match_indices("<DataArray")
                .map(|(i, _)| {
                    let j = header[i..].find('>').expect(">") + i;
                    header[i..=j].to_string()
                })
                .collect();
            // Walk the arrays, each right after the one before, to the end
            // of the binary section.
            let (mut end, mut payloads, mut stored) = (0usize, Vec::new(), Vec::new());
            for a in &arrays {
                assert_eq!(attr(a, "format"), Some("appended"));
                let off: usize = attr(a, "offset").expect("offset").parse().expect("int");
                assert_eq!(off, end, "arrays follow each other");
                let (values, len) = if zlib {
                    unzip(raw, off)
                } else {
                    let len = u64_at(raw, off) as usize;
                    (raw[off + 8..off + 8 + len].to_vec(), 8 + len)
                };
                payloads.push(values);
                stored.push(len);
                end = off + len;
            }
            let tail = String::from_utf8(raw[end..].to_vec()).expect("utf8 tail");
            assert_eq!(tail.trim(), "</AppendedData>\n</VTKFile>");
            let xml = format!("{header}{tail}");
            Vtk {
                xml,
                arrays,
                payloads,
                stored,
            }
        }

        fn index(&self, name: &str) -> usize {
            self.arrays
                .iter()
                .position(|a| attr(a, "Name") == Some(name))
                .unwrap_or_else(|| panic!("no array {name}"))
        }

        fn tag(&self, name: &str) -> &str {
            &self.arrays[self.index(name)]
        }

        /// Values of the named array (decompressed).
        fn payload(&self, name: &str) -> &[u8] {
            &self.payloads[self.index(name)]
        }

        fn f64s(&self, name: &str) -> Vec<f64> {
            assert_eq!(attr(self.tag(name), "type"), Some("Float64"));
            self.payload(name)
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8")))
                .collect()
        }

        fn i64s(&self, name: &str) -> Vec<i64> {
            assert_eq!(attr(self.tag(name), "type"), Some("Int64"));
            self.payload(name)
                .chunks_exact(8)
                .map(|c| i64::from_le_bytes(c.try_into().expect("8")))
                .collect()
        }
    }

    /// Every way of storing the arrays the tests check.
    const COMPRESSIONS: [Compression; 3] = [
        Compression::None,
        Compression::Zlib { level: 1 },
        Compression::Zlib { level: 9 },
    ];

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    #[test]
    fn vtu_round_trips_exactly() {
        let dir = test_dir("vtu");
        for (i, z) in COMPRESSIONS.into_iter().enumerate() {
            let path = dir.join(format!("p{i}.vtu"));
            let points = [[0.0, 1.5, -2.0], [1e-300, f64::MAX, -0.0], [0.1, 0.2, 0.3]];
            let mass = [1.0, 2.0 / 3.0, f64::NAN];
            let vel = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [-7.0, 8.5, 1e10]];
            let stress: Vec<[f64; 9]> = (0..3)
                .map(|p| std::array::from_fn(|k| (p * 9 + k) as f64 * 0.37 - 1.0))
                .collect();
            write_vtu_points(
                &path,
                &points,
                &[
                    Field::scalar("mass", &mass),
                    Field::vector("velocity", &vel),
                    Field::tensor("stress & <strain>", &stress),
                ],
                z,
            )
            .expect("write vtu");

            let v = Vtk::read(&path);
            assert_balanced(&v.xml);
            assert!(v.xml.contains("type=\"UnstructuredGrid\""));
            assert!(v.xml.contains("NumberOfPoints=\"3\" NumberOfCells=\"3\""));
            assert_eq!(bits(&v.f64s("mass")), bits(&mass));
            assert_eq!(attr(v.tag("velocity"), "NumberOfComponents"), Some("3"));
            let flat_vel: Vec<f64> = vel.iter().flatten().copied().collect();
            assert_eq!(bits(&v.f64s("velocity")), bits(&flat_vel));
            let tname = "stress &amp; &lt;strain&gt;";
            assert_eq!(attr(v.tag(tname), "NumberOfComponents"), Some("9"));
            let flat_s: Vec<f64> = stress.iter().flatten().copied().collect();
            assert_eq!(bits(&v.f64s(tname)), bits(&flat_s));
            let flat_p: Vec<f64> = points.iter().flatten().copied().collect();
            assert_eq!(bits(&v.f64s("Points")), bits(&flat_p));
            assert_eq!(v.i64s("connectivity"), vec![0, 1, 2]);
            assert_eq!(v.i64s("offsets"), vec![1, 2, 3]);
            assert_eq!(attr(v.tag("types"), "type"), Some("UInt8"));
            assert_eq!(v.payload("types"), &[VTK_VERTEX; 3]);
        }
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn vtu_zero_points_is_valid() {
        let dir = test_dir("vtu0");
        for (i, z) in COMPRESSIONS.into_iter().enumerate() {
            let path = dir.join(format!("empty{i}.vtu"));
            write_vtu_points(&path, &[], &[Field::scalar("mass", &[])], z).expect("write");
            let v = Vtk::read(&path);
            assert_balanced(&v.xml);
            assert!(v.xml.contains("NumberOfPoints=\"0\" NumberOfCells=\"0\""));
            for name in ["mass", "Points", "connectivity", "offsets", "types"] {
                assert!(v.payload(name).is_empty(), "{name}");
            }
        }
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn vti_round_trips_exactly_3d_and_2d() {
        let dir = test_dir("vti");
        for (i, z) in COMPRESSIONS.into_iter().enumerate() {
            // 3D: 2 x 3 x 1 cells -> 3*4*2 = 24 points, 6 cells.
            let path = dir.join(format!("g3_{i}.vti"));
            let pressure: Vec<f64> = (0..24).map(|i| (i as f64).sqrt() - 2.0).collect();
            let vel: Vec<[f64; 3]> = (0..24).map(|i| [i as f64, -(i as f64), 0.5]).collect();
            let vol_frac: Vec<f64> = (0..6).map(|i| i as f64 / 7.0).collect();
            let stress: Vec<[f64; 9]> = (0..6).map(|i| [i as f64 * 1e-7; 9]).collect();
            write_vti(
                &path,
                [0.0, -1.0, 2.5e-8],
                [0.1, 0.2, 1e20],
                [2, 3, 1],
                &[
                    Field::scalar("pressure", &pressure),
                    Field::vector("velocity", &vel),
                ],
                &[
                    Field::scalar("vol_frac", &vol_frac),
                    Field::tensor("stress", &stress),
                ],
                z,
            )
            .expect("write vti");
            let v = Vtk::read(&path);
            assert_balanced(&v.xml);
            assert!(v.xml.contains("WholeExtent=\"0 2 0 3 0 1\""));
            assert!(v.xml.contains("Piece Extent=\"0 2 0 3 0 1\""));
            assert!(v.xml.contains("Origin=\"0 -1 2.5e-8\""));
            assert!(v.xml.contains("Spacing=\"0.1 0.2 1e20\""));
            assert_eq!(bits(&v.f64s("pressure")), bits(&pressure));
            let flat: Vec<f64> = vel.iter().flatten().copied().collect();
            assert_eq!(bits(&v.f64s("velocity")), bits(&flat));
            assert_eq!(bits(&v.f64s("vol_frac")), bits(&vol_frac));
            let flat: Vec<f64> = stress.iter().flatten().copied().collect();
            assert_eq!(bits(&v.f64s("stress")), bits(&flat));

            // 2D: 4 x 2 cells -> 5*3 = 15 points, 8 cells; no cell data.
            let path = dir.join(format!("g2_{i}.vti"));
            let phi: Vec<f64> = (0..15).map(|i| i as f64 * 0.25).collect();
            write_vti(
                &path,
                [0.0; 3],
                [1.0; 3],
                [4, 2, 0],
                &[Field::scalar("phi", &phi)],
                &[],
                z,
            )
            .expect("write 2d");
            let v = Vtk::read(&path);
            assert_balanced(&v.xml);
            assert!(v.xml.contains("WholeExtent=\"0 4 0 2 0 0\""));
            assert!(v.xml.contains("<CellData/>"));
            assert_eq!(bits(&v.f64s("phi")), bits(&phi));
        }
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    /// zlib files hold the raw files' values exactly, however the arrays
    /// fall on blocks and batches: arrays of several batches with a partial
    /// last block, of exactly one block, computed fields, quads; and the
    /// structured arrays (connectivity, types, zero z) shrink.
    #[test]
    fn zlib_holds_the_raw_values_across_blocks_and_batches() {
        let dir = test_dir("vtk-zlib");
        // 200 001 points: Points is 4.8 MB, three batches of 64 blocks and
        // a partial last block.
        let n = 200_001;
        let pts: Vec<[f64; 3]> = (0..n)
            .map(|i| [(i as f64 * 0.618).sin(), (i as f64).sqrt(), 0.0])
            .collect();
        let mass: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64 / 3.0).collect();
        let twice = |i: usize, o: &mut [f64]| o[0] = 2.0 * mass[i];
        let fields = [
            Field::scalar("mass", &mass),
            Field {
                name: "twice",
                data: FieldData::Computed {
                    n,
                    components: 1,
                    f: &twice,
                },
            },
        ];
        // 64 x 64 cells: a cell field of exactly one block.
        let cells = 64 * 64;
        let rho: Vec<f64> = (0..cells).map(|i| (i as f64).ln_1p()).collect();
        let quad_pts = [[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let quads = [[0, 1, 2, 3]];
        let tension = [3.5];
        let mut files = Vec::new();
        for (i, z) in COMPRESSIONS.into_iter().enumerate() {
            let vtu = dir.join(format!("p{i}.vtu"));
            write_vtu_points(&vtu, &pts, &fields, z).expect("vtu");
            let vti = dir.join(format!("g{i}.vti"));
            let cell = [Field::scalar("rho", &rho)];
            write_vti(&vti, [0.0; 3], [1.0; 3], [64, 64, 0], &[], &cell, z).expect("vti");
            let quad = dir.join(format!("q{i}.vtu"));
            let t = [Field::scalar("tension", &tension)];
            write_vtu_quads(&quad, &quad_pts, &quads, &[], &t, z).expect("quads");
            files.push([vtu, vti, quad].map(|p| Vtk::read(&p)));
        }
        let [raw, fast, small] = &files[..] else {
            unreachable!()
        };
        for k in 0..3 {
            for zipped in [&fast[k], &small[k]] {
                assert_eq!(zipped.arrays.len(), raw[k].arrays.len());
                for (a, b) in zipped.payloads.iter().zip(&raw[k].payloads) {
                    assert!(a == b, "file {k}: a decoded array differs from the raw one");
                }
                assert!(zipped.xml.contains("compressor=\"vtkZLibDataCompressor\""));
            }
        }
        assert_eq!(
            bits(&fast[0].f64s("twice")),
            bits(&mass.iter().map(|m| 2.0 * m).collect::<Vec<_>>())
        );
        assert_eq!(fast[1].payload("rho").len(), ZLIB_BLOCK);
        // Connectivity and offsets (counting numbers as 8-byte integers,
        // of which 2 or 3 bytes change: 5.3-fold measured) shrink at least
        // 4-fold and the types (one repeated byte) 100-fold at either level.
        for z in [fast, small] {
            for (name, factor) in [("connectivity", 4), ("offsets", 4), ("types", 100)] {
                let i = z[0].index(name);
                assert!(factor * z[0].stored[i] < raw[0].stored[i], "{name}");
            }
        }
        let total = |f: &[Vtk; 3]| f[0].stored.iter().sum::<usize>();
        assert!(total(small) <= total(fast) && total(fast) < total(raw));
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn wrong_lengths_are_invalid_input_naming_the_field() {
        let dir = test_dir("vtk-bad");
        let path = dir.join("bad.vti");
        let p = vec![0.0; 15];
        let c_bad = vec![0.0; 7];
        let err = write_vti(
            &path,
            [0.0; 3],
            [1.0; 3],
            [4, 2, 0],
            &[Field::scalar("phi", &p)],
            &[Field::scalar("rho", &c_bad)],
            Compression::None,
        )
        .expect_err("bad cell length");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains("\"rho\""), "{err}");

        let err = write_vti(
            &path,
            [0.0; 3],
            [1.0; 3],
            [4, 2, 0],
            &[Field::scalar("phi", &p[..14])],
            &[],
            Compression::None,
        )
        .expect_err("bad point length");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains("\"phi\""), "{err}");

        let err = write_vti(
            &path,
            [f64::NAN, 0.0, 0.0],
            [1.0; 3],
            [1, 1, 1],
            &[],
            &[],
            Compression::None,
        )
        .expect_err("nan origin");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);

        let err = write_vti(
            &path,
            [0.0; 3],
            [1.0; 3],
            [usize::MAX, 2, 2],
            &[],
            &[],
            Compression::None,
        )
        .expect_err("overflow");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);

        let vpath = dir.join("bad.vtu");
        let vel = [[0.0; 3]; 2];
        let err = write_vtu_points(
            &vpath,
            &[[0.0; 3]; 3],
            &[Field::vector("vel", &vel)],
            Compression::None,
        )
        .expect_err("bad vtu length");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains("\"vel\""), "{err}");

        let m = [1.0; 3];
        let err = write_vtu_points(
            &vpath,
            &[[0.0; 3]; 3],
            &[Field::scalar("m", &m), Field::scalar("m", &m)],
            Compression::None,
        )
        .expect_err("duplicate");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);

        for level in [0, 10] {
            let err = write_vtu_points(&vpath, &[[0.0; 3]], &[], Compression::Zlib { level })
                .expect_err("bad level");
            assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
            assert!(err.to_string().contains(&format!("level {level}")), "{err}");
        }

        // Nothing was written, not even temporaries.
        assert_eq!(fs::read_dir(&dir).expect("dir").count(), 0);
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn pvd_lists_entries_and_is_rewritten() {
        let dir = test_dir("pvd");
        let path = dir.join("particles.pvd");
        let mut s = PvdSeries::new(&path);
        assert!(s.is_empty());
        s.push(0.0, "particles_0000.vtu").expect("push 0");
        let first = fs::read_to_string(&path).expect("read");
        assert_balanced(&first);
        assert_eq!(first.matches("<DataSet").count(), 1);
        s.push(2.5e-3, "particles_0001.vtu").expect("push 1");
        s.push(1e-9, "a&b.vtu").expect("push 2");
        assert_eq!(s.len(), 3);

        let text = fs::read_to_string(&path).expect("read");
        assert_balanced(&text);
        assert!(text.contains("type=\"Collection\""));
        let sets: Vec<(String, String)> = text
            .lines()
            .filter(|l| l.contains("<DataSet"))
            .map(|l| {
                (
                    attr(l, "timestep").expect("timestep").to_string(),
                    attr(l, "file").expect("file").to_string(),
                )
            })
            .collect();
        assert_eq!(
            sets,
            vec![
                ("0".to_string(), "particles_0000.vtu".to_string()),
                ("0.0025".to_string(), "particles_0001.vtu".to_string()),
                ("1e-9".to_string(), "a&amp;b.vtu".to_string()),
            ]
        );
        let err = s.push(f64::NAN, "x.vtu").expect_err("nan time");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert_eq!(s.len(), 3);
        // Only the .pvd itself: no temporary files left behind.
        assert_eq!(fs::read_dir(&dir).expect("dir").count(), 1);
        fs::remove_dir_all(&dir).expect("cleanup");
    }
}
