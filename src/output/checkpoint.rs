//! Checkpoint folders: a `manifest.json` plus one NumPy `.npy` file per array.
//!
//! A checkpoint holds everything a model and the run loop need to continue a
//! run bit-identically: named arrays of `f64` or `u64` (each one `.npy` file
//! that `numpy.load` opens), a few small values in `meta` (integers, strings),
//! and a header naming the model kind, the scene (by content hash), the step
//! and the time.
//!
//! ```text
//! ckpt_000120/
//!   manifest.json        format_version, scene_hash, model, step, time + time_bits,
//!                        arrays (name, file, dtype, shape, bytes, checksum), meta
//!   particles.x.npy      '<f8', C order
//!   ...
//! ```
//!
//! [`Checkpoint::write`] writes the whole folder under a temporary sibling name
//! and renames it into place, so a killed run leaves either no checkpoint or a
//! complete one. [`Checkpoint::read`] checks everything it can before handing
//! data back: the format version, the scene hash, each file's size, checksum
//! (64-bit FNV-1a, [`content_hash`]), dtype and shape, and that the decimal
//! `time` agrees with its exact bit pattern `time_bits`.
//!
//! This module depends on `std`, `serde`, `serde_json`, `thiserror` and `npyz`
//! only.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::io;
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

/// Version written by this build; a checkpoint with a larger version is
/// rejected.
pub const FORMAT_VERSION: u32 = 1;

/// Name of the manifest file inside a checkpoint folder.
pub const MANIFEST_FILE: &str = "manifest.json";

/// Largest `.npy` header text accepted (NumPy's own default `max_header_size`).
const NPY_MAX_HEADER: usize = 10_000;

/// Deepest bracket nesting accepted in a `.npy` header. A plain-dtype header
/// (`{'descr': '<f8', 'fortran_order': False, 'shape': (n, 3), }`) nests 2
/// deep; the bound keeps the recursive header parser away from deep inputs.
const NPY_MAX_DEPTH: usize = 4;

/// Prefix of [`content_hash`] strings.
const HASH_PREFIX: &str = "fnv1a64:";

/// Counter making temporary folder names unique within one process.
static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Element type of a stored array.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Dtype {
    /// 64-bit float, stored little-endian (`'<f8'`).
    F64,
    /// 64-bit unsigned integer, stored little-endian (`'<u8'`).
    U64,
}

impl Dtype {
    /// The NumPy type string of this dtype in the `.npy` header.
    pub fn npy_descr(self) -> &'static str {
        match self {
            Dtype::F64 => "<f8",
            Dtype::U64 => "<u8",
        }
    }

    /// The name used in the manifest and in messages (`f64`, `u64`).
    pub fn name(self) -> &'static str {
        match self {
            Dtype::F64 => "f64",
            Dtype::U64 => "u64",
        }
    }
}

/// The values of one array, flattened in C (row-major) order.
#[derive(Debug, Clone, PartialEq)]
pub enum ArrayData {
    /// `f64` values.
    F64(Vec<f64>),
    /// `u64` values.
    U64(Vec<u64>),
}

/// An element type of checkpoint arrays (`f64`, `u64`): its dtype and how
/// its values sit in [`ArrayData`].
pub trait Element: Copy + npyz::Serialize {
    /// The dtype written for this type.
    const DTYPE: Dtype;
    /// The values of `data` if they are of this type.
    fn buffer(data: &mut ArrayData) -> Option<&mut Vec<Self>>;
    /// Wraps values of this type.
    fn wrap(v: Vec<Self>) -> ArrayData;
    /// The value as stored in a `.npy` file (little-endian).
    fn le_bytes(self) -> [u8; 8];
}

impl Element for f64 {
    const DTYPE: Dtype = Dtype::F64;
    fn buffer(data: &mut ArrayData) -> Option<&mut Vec<f64>> {
        match data {
            ArrayData::F64(v) => Some(v),
            ArrayData::U64(_) => None,
        }
    }
    fn wrap(v: Vec<f64>) -> ArrayData {
        ArrayData::F64(v)
    }
    fn le_bytes(self) -> [u8; 8] {
        self.to_le_bytes()
    }
}

impl Element for u64 {
    const DTYPE: Dtype = Dtype::U64;
    fn buffer(data: &mut ArrayData) -> Option<&mut Vec<u64>> {
        match data {
            ArrayData::U64(v) => Some(v),
            ArrayData::F64(_) => None,
        }
    }
    fn wrap(v: Vec<u64>) -> ArrayData {
        ArrayData::U64(v)
    }
    fn le_bytes(self) -> [u8; 8] {
        self.to_le_bytes()
    }
}

impl ArrayData {
    /// The element type.
    pub fn dtype(&self) -> Dtype {
        match self {
            ArrayData::F64(_) => Dtype::F64,
            ArrayData::U64(_) => Dtype::U64,
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        match self {
            ArrayData::F64(v) => v.len(),
            ArrayData::U64(v) => v.len(),
        }
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One array as listed in the manifest.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ArrayEntry {
    /// Array name (`[A-Za-z0-9_.]+`).
    pub name: String,
    /// File name inside the folder, always `<name>.npy`.
    pub file: String,
    /// Element type.
    pub dtype: Dtype,
    /// Shape (C order); the product is the number of elements.
    pub shape: Vec<usize>,
    /// Size of the `.npy` file in bytes.
    pub bytes: u64,
    /// [`content_hash`] of the whole `.npy` file.
    pub checksum: String,
}

/// The parsed `manifest.json` of a checkpoint.
///
/// On disk the manifest also holds `time_bits`, the exact bit pattern of
/// `time` as `"0x<16 hex digits>"` (an integer is accepted too); `time` is
/// written as a JSON number (`null` when it is not finite) and must agree with
/// `time_bits` bit for bit when read. Unknown extra fields are ignored.
/// Deserializing checks the manifest's internal consistency (names, file
/// names, checksum syntax, shapes, time).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(into = "ManifestFile", try_from = "ManifestFile")]
pub struct Manifest {
    /// Format version of the folder layout ([`FORMAT_VERSION`] when written).
    pub format_version: u32,
    /// Content hash of the scene the run was started from.
    pub scene_hash: String,
    /// Model kind, e.g. `explicit_solid<2>`.
    pub model: String,
    /// Completed step count.
    pub step: u64,
    /// Simulation time.
    pub time: f64,
    /// The arrays, sorted by name.
    pub arrays: Vec<ArrayEntry>,
    /// Small run-loop and model state (integers, strings).
    pub meta: Map<String, Value>,
}

/// The manifest exactly as stored in `manifest.json`.
#[derive(Clone, Serialize, Deserialize)]
struct ManifestFile {
    format_version: u32,
    scene_hash: String,
    model: String,
    step: u64,
    /// `None` (JSON `null`) when the time is not finite.
    time: Option<f64>,
    /// `"0x<16 hex digits>"` on write; a hex string or an integer on read.
    time_bits: Value,
    arrays: Vec<ArrayEntry>,
    #[serde(default)]
    meta: Map<String, Value>,
}

impl From<Manifest> for ManifestFile {
    fn from(m: Manifest) -> Self {
        ManifestFile {
            format_version: m.format_version,
            scene_hash: m.scene_hash,
            model: m.model,
            step: m.step,
            time: m.time.is_finite().then_some(m.time),
            time_bits: Value::String(format!("0x{:016x}", m.time.to_bits())),
            arrays: m.arrays,
            meta: m.meta,
        }
    }
}

impl TryFrom<ManifestFile> for Manifest {
    type Error = String;

    fn try_from(f: ManifestFile) -> Result<Self, String> {
        let bits = parse_time_bits(&f.time_bits)?;
        let time = f64::from_bits(bits);
        match f.time {
            Some(t) if t.to_bits() == bits => {}
            Some(t) => {
                return Err(format!(
                    "time {t:e} does not match time_bits {} ({time:e})",
                    f.time_bits
                ))
            }
            None if !time.is_finite() => {}
            None => {
                return Err(format!(
                    "time is null but time_bits {} is the finite time {time:e}",
                    f.time_bits
                ))
            }
        }
        if f.format_version == 0 {
            return Err("format_version 0 is not a valid version".to_string());
        }
        let mut names = BTreeSet::new();
        for e in &f.arrays {
            check_name(&e.name)?;
            if e.file != npy_file_name(&e.name) {
                return Err(format!(
                    "array `{}` is stored in `{}`, expected `{}`",
                    e.name,
                    e.file,
                    npy_file_name(&e.name)
                ));
            }
            if !names.insert(e.name.as_str()) {
                return Err(format!("array `{}` is listed twice", e.name));
            }
            if data_bytes(&e.shape).is_none() {
                return Err(format!(
                    "array `{}` has an impossible shape {:?}",
                    e.name, e.shape
                ));
            }
            if !is_hash(&e.checksum) {
                return Err(format!(
                    "array `{}` has checksum `{}`, expected `{HASH_PREFIX}<16 hex digits>`",
                    e.name, e.checksum
                ));
            }
        }
        Ok(Manifest {
            format_version: f.format_version,
            scene_hash: f.scene_hash,
            model: f.model,
            step: f.step,
            time,
            arrays: f.arrays,
            meta: f.meta,
        })
    }
}

/// Reads `time_bits`: `"0x<hex>"` or a JSON integer.
fn parse_time_bits(v: &Value) -> Result<u64, String> {
    let parsed = match v {
        Value::Number(n) => n.as_u64(),
        Value::String(s) => s
            .strip_prefix("0x")
            .and_then(|h| u64::from_str_radix(h, 16).ok()),
        _ => None,
    };
    parsed.ok_or_else(|| format!("time_bits {v} is not a 64-bit hex string or integer"))
}

/// Whether `s` is `fnv1a64:` followed by 16 lowercase hex digits.
fn is_hash(s: &str) -> bool {
    s.strip_prefix(HASH_PREFIX)
        .is_some_and(|h| h.len() == 16 && h.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f')))
}

/// Checks an array name against `[A-Za-z0-9_.]+`.
fn check_name(name: &str) -> Result<(), String> {
    let ok = !name.is_empty()
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'.');
    if ok {
        Ok(())
    } else {
        Err(format!(
            "array name `{name}` is not allowed (use letters, digits, `_` and `.`)"
        ))
    }
}

/// `<name>.npy`.
fn npy_file_name(name: &str) -> String {
    format!("{name}.npy")
}

/// Number of elements of `shape`, if it fits in `usize`.
fn element_count(shape: &[usize]) -> Option<usize> {
    shape.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d))
}

/// Bytes of the data part for `shape` (8 per element), if it fits in `usize`.
fn data_bytes(shape: &[usize]) -> Option<usize> {
    element_count(shape)?.checked_mul(8)
}

/// 64-bit FNV-1a of `bytes` as `"fnv1a64:<16 lowercase hex digits>"`.
///
/// Stable across platforms and Rust versions; used for the array checksums
/// and, by the run loop, for the scene hash.
pub fn content_hash(bytes: &[u8]) -> String {
    hash_string(fnv1a(FNV_OFFSET_BASIS, bytes))
}

/// The 64-bit FNV-1a offset basis: the hash of no bytes.
const FNV_OFFSET_BASIS: u64 = 0xcbf2_9ce4_8422_2325;

/// FNV-1a of `bytes`, continued from the hash `h` of the bytes before them.
fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(PRIME);
    }
    h
}

/// A hash as a manifest writes it.
fn hash_string(h: u64) -> String {
    format!("{HASH_PREFIX}{h:016x}")
}

/// Why a checkpoint could not be written, read or taken apart.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// An operating-system error on `path`.
    #[error("checkpoint I/O error on {}: {source}", .path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// The folder has no `manifest.json` (or does not exist).
    #[error("{} is not a checkpoint folder (no {MANIFEST_FILE})", .dir.display())]
    NotACheckpoint {
        /// The folder.
        dir: PathBuf,
    },
    /// The manifest cannot be parsed or is inconsistent.
    #[error("checkpoint manifest {} is invalid: {reason}", .path.display())]
    Manifest {
        /// Path of `manifest.json`.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The checkpoint was written by a newer build.
    #[error("checkpoint {} has format version {found}; this build reads up to {supported}", .dir.display())]
    NewerVersion {
        /// The folder.
        dir: PathBuf,
        /// Version in the manifest.
        found: u32,
        /// [`FORMAT_VERSION`].
        supported: u32,
    },
    /// The checkpoint belongs to another scene.
    #[error("checkpoint {} was written for another scene (scene hash {found}, this scene {expected})", .dir.display())]
    SceneMismatch {
        /// The folder.
        dir: PathBuf,
        /// Hash of the current scene.
        expected: String,
        /// Hash in the manifest.
        found: String,
    },
    /// An array file's size differs from the manifest.
    #[error("checkpoint {}: {} {}: {found} bytes, manifest says {expected}",
        folder_of(.file), file_name_of(.file),
        if .found < .expected { "is truncated" } else { "is longer than listed" })]
    Truncated {
        /// The array file.
        file: PathBuf,
        /// Size in the manifest.
        expected: u64,
        /// Size on disk.
        found: u64,
    },
    /// An array file's content hash differs from the manifest.
    #[error("checkpoint {}: {} is corrupt: checksum {found}, manifest says {expected}",
        folder_of(.file), file_name_of(.file))]
    Checksum {
        /// The array file.
        file: PathBuf,
        /// Checksum in the manifest.
        expected: String,
        /// Checksum of the file.
        found: String,
    },
    /// An array file is not a valid `.npy` of the listed dtype and shape, or
    /// an array cannot be written (shape does not match the data, bad name).
    #[error("checkpoint {}: array file {}: {reason}", folder_of(.file), file_name_of(.file))]
    Array {
        /// The array file.
        file: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// An array or meta key is absent.
    #[error("{what} is missing")]
    Missing {
        /// Which array or key, with the checkpoint folder when known.
        what: String,
    },
    /// An array or meta value has the wrong dtype, shape or type.
    #[error("{what}: {reason}")]
    Malformed {
        /// Which array or key, with the checkpoint folder when known.
        what: String,
        /// What is wrong.
        reason: String,
    },
    /// The target folder of a write already exists.
    #[error("checkpoint {} already exists (each checkpoint needs a new folder)", .dir.display())]
    Exists {
        /// The folder.
        dir: PathBuf,
    },
}

/// The folder part of an array-file path, for messages.
fn folder_of(file: &Path) -> String {
    file.parent()
        .map(|p| p.display().to_string())
        .unwrap_or_default()
}

/// The file-name part of an array-file path, for messages.
fn file_name_of(file: &Path) -> String {
    file.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| file.display().to_string())
}

fn io_err(path: &Path) -> impl FnOnce(io::Error) -> CheckpointError + '_ {
    move |source| CheckpointError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// A checkpoint in memory: header, named arrays and meta values.
///
/// Build one with [`Checkpoint::new`] and the `put_*`/[`Checkpoint::set_meta`]
/// methods, then [`Checkpoint::write`] it; or [`Checkpoint::read`] one and take
/// its arrays apart with the `take_*` and `meta*` methods.
#[derive(Debug, Clone)]
pub struct Checkpoint {
    model: String,
    scene_hash: String,
    step: u64,
    time: f64,
    arrays: BTreeMap<String, (Vec<usize>, ArrayData)>,
    meta: Map<String, Value>,
    /// Folder this checkpoint was read from (for messages).
    source: Option<PathBuf>,
    /// Where the arrays go as they are put.
    store: Store,
}

/// Where a checkpoint's arrays go as they are put.
#[derive(Debug, Clone, Default)]
enum Store {
    /// Kept in memory, in `Checkpoint::arrays`.
    #[default]
    Memory,
    /// Written to their files as they are put ([`Checkpoint::streaming`]).
    Stream(Box<Stream>),
    /// Only their size in bytes summed ([`Checkpoint::measuring`]).
    Measure(u64),
}

/// A checkpoint streamed to a folder: the arrays written so far (dtype,
/// shape, file size and, for a checkpoint folder, checksum) and the first
/// error met (reported by [`Checkpoint::seal`]). A working copy
/// ([`Checkpoint::streaming`]) has no manifest and no checksums (hashing a
/// large state took longer than writing it); [`Checkpoint::to_memory`]
/// reads it back from these entries. A checkpoint folder
/// ([`Checkpoint::streaming_folder`]) gets its manifest when written.
#[derive(Debug, Clone)]
struct Stream {
    dir: PathBuf,
    /// Whether the files are hashed (a checkpoint folder).
    checksums: bool,
    entries: BTreeMap<String, (Dtype, Vec<usize>, u64, Option<u64>)>,
    error: Option<(PathBuf, io::ErrorKind, String)>,
    /// The write buffer, kept between arrays and captures.
    buf: Vec<u8>,
}

impl Stream {
    /// Writes the array `name` of `shape` as its `.npy` file, its values from
    /// `fill`; records its entry, or the error.
    fn write<T: Element>(
        &mut self,
        name: &str,
        shape: Vec<usize>,
        fill: impl FnOnce(&mut ArrayFill<'_, T>),
    ) {
        if self.error.is_some() {
            return;
        }
        let path = self.dir.join(npy_file_name(name));
        match stream_array(&path, &shape, &mut self.buf, self.checksums, fill) {
            Ok((bytes, hash)) => {
                self.entries
                    .insert(name.to_string(), (T::DTYPE, shape, bytes, hash));
            }
            Err(e) => self.error = Some((path, e.kind(), e.to_string())),
        }
    }
}

/// Writes one array's `.npy` file at `path` from `fill`, without holding its
/// values, byte for byte as [`Checkpoint::write`] does; returns its size
/// and, where asked, its FNV-1a hash.
fn stream_array<T: Element>(
    path: &Path,
    shape: &[usize],
    buf: &mut Vec<u8>,
    checksum: bool,
    fill: impl FnOnce(&mut ArrayFill<'_, T>),
) -> io::Result<(u64, Option<u64>)> {
    // The header as the `.npy` writer makes it; the values follow as they
    // are stored, little-endian.
    buf.clear();
    drop(super::npy::begin::<T, _>(
        &mut *buf,
        T::DTYPE.npy_descr(),
        shape,
    )?);
    let header = buf.len() as u64;
    let mut target = ArrayFill(FillTarget::File(FileFill {
        // Opened without truncating: the next capture overwrites a file of
        // the same size in place, which took a fifth of the time of
        // truncating it and writing it anew.
        file: fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)?,
        buf,
        hash: checksum.then_some(FNV_OFFSET_BASIS),
        count: 0,
        error: None,
        _values: std::marker::PhantomData,
    }));
    fill(&mut target);
    let FillTarget::File(mut f) = target.0 else {
        unreachable!("a streamed fill writes to its file");
    };
    if let Some(e) = f.error.take() {
        return Err(e);
    }
    if element_count(shape) != Some(f.count) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "shape {shape:?} does not match the {} values given",
                f.count
            ),
        ));
    }
    f.drain();
    if let Some(e) = f.error {
        return Err(e);
    }
    let bytes = header + 8 * f.count as u64;
    f.file.set_len(bytes)?;
    Ok((bytes, f.hash))
}

/// Where a [`Checkpoint::put_f64_with`] fill puts an array's values, in C
/// order: the checkpoint's buffer for the array, or the array's `.npy` file
/// when the checkpoint is streamed ([`Checkpoint::streaming`]), so that a
/// streamed state never holds a copy of an array.
pub struct ArrayFill<'a, T: Element>(FillTarget<'a, T>);

enum FillTarget<'a, T: Element> {
    Buffer(&'a mut Vec<T>),
    File(FileFill<'a, T>),
}

/// An array being written to its file: the values given and the first error.
struct FileFill<'a, T: Element> {
    file: fs::File,
    /// The bytes not written yet (the stream's buffer, kept between arrays
    /// and captures).
    buf: &'a mut Vec<u8>,
    /// FNV-1a of the bytes written so far, where the file is hashed.
    hash: Option<u64>,
    count: usize,
    error: Option<io::Error>,
    _values: std::marker::PhantomData<T>,
}

impl<T: Element> FileFill<'_, T> {
    /// Bytes gathered before a write: values serialised into one buffer
    /// and written in large pieces run at the page cache's speed (one
    /// buffered write a value took three times as long).
    const CHUNK: usize = 1 << 18;

    /// Writes the gathered bytes (unless an error came first).
    fn drain(&mut self) {
        if let Some(h) = &mut self.hash {
            *h = fnv1a(*h, self.buf);
        }
        if self.error.is_none() {
            if let Err(e) = io::Write::write_all(&mut self.file, self.buf) {
                self.error = Some(e);
            }
        }
        self.buf.clear();
    }
}

impl<T: Element> ArrayFill<'_, T> {
    /// Appends `values`.
    pub fn extend_from_slice(&mut self, values: &[T]) {
        match &mut self.0 {
            FillTarget::Buffer(b) => b.extend_from_slice(values),
            FillTarget::File(f) => {
                // A chunk at a time, into room made once (a tight loop).
                for chunk in values.chunks(FileFill::<T>::CHUNK / 8) {
                    let start = f.buf.len();
                    f.buf.resize(start + 8 * chunk.len(), 0);
                    for (b, v) in f.buf[start..].chunks_exact_mut(8).zip(chunk) {
                        b.copy_from_slice(&v.le_bytes());
                    }
                    f.count += chunk.len();
                    if f.buf.len() >= FileFill::<T>::CHUNK {
                        f.drain();
                    }
                }
            }
        }
    }
}

impl<T: Element> Extend<T> for ArrayFill<'_, T> {
    fn extend<I: IntoIterator<Item = T>>(&mut self, values: I) {
        match &mut self.0 {
            FillTarget::Buffer(b) => b.extend(values),
            FillTarget::File(f) => {
                for v in values {
                    f.count += 1;
                    f.buf.extend_from_slice(&v.le_bytes());
                    if f.buf.len() >= FileFill::<T>::CHUNK {
                        f.drain();
                    }
                }
            }
        }
    }
}

impl<'v, T: Element> Extend<&'v T> for ArrayFill<'_, T> {
    fn extend<I: IntoIterator<Item = &'v T>>(&mut self, values: I) {
        self.extend(values.into_iter().copied());
    }
}

impl Checkpoint {
    /// An empty checkpoint of `model` at `step` and `time`.
    pub fn new(model: &str, scene_hash: &str, step: u64, time: f64) -> Self {
        Checkpoint {
            model: model.to_string(),
            scene_hash: scene_hash.to_string(),
            step,
            time,
            arrays: BTreeMap::new(),
            meta: Map::new(),
            source: None,
            store: Store::Memory,
        }
    }

    /// An empty checkpoint of `model` at `step` and `time` whose arrays are
    /// written to `<dir>/<name>.npy` as they are put and not kept in memory:
    /// a state saved this way costs no memory beyond a file buffer. `dir`
    /// is created if needed; files of the same names are overwritten, in
    /// place. Unlike [`Checkpoint::write`] nothing is atomic and no manifest
    /// is written: the folder is this checkpoint's working copy, not a
    /// checkpoint folder. Finish it with [`Checkpoint::seal`], read it back
    /// with [`Checkpoint::to_memory`].
    ///
    /// # Errors
    /// [`CheckpointError::Io`] if `dir` cannot be created.
    pub fn streaming(
        dir: &Path,
        model: &str,
        scene_hash: &str,
        step: u64,
        time: f64,
    ) -> Result<Self, CheckpointError> {
        Self::stream_to(dir, false, model, scene_hash, step, time)
    }

    /// An empty checkpoint streamed, as [`Checkpoint::streaming`], into the
    /// folder `tmp`, its files hashed as they are written, so that
    /// [`Checkpoint::write`] makes it the checkpoint folder `dir` by adding
    /// the manifest and renaming `tmp` to `dir`: a checkpoint of a large
    /// state written without a copy of it in memory, and atomic as any
    /// other. `tmp` should be a fresh sibling of the folders it will be
    /// written as (a rename does not cross file systems).
    ///
    /// # Errors
    /// [`CheckpointError::Io`] if `tmp` cannot be created.
    pub fn streaming_folder(
        tmp: &Path,
        model: &str,
        scene_hash: &str,
        step: u64,
        time: f64,
    ) -> Result<Self, CheckpointError> {
        Self::stream_to(tmp, true, model, scene_hash, step, time)
    }

    fn stream_to(
        dir: &Path,
        checksums: bool,
        model: &str,
        scene_hash: &str,
        step: u64,
        time: f64,
    ) -> Result<Self, CheckpointError> {
        fs::create_dir_all(dir).map_err(io_err(dir))?;
        let mut ck = Self::new(model, scene_hash, step, time);
        ck.store = Store::Stream(Box::new(Stream {
            dir: dir.to_path_buf(),
            checksums,
            entries: BTreeMap::new(),
            error: None,
            buf: Vec::new(),
        }));
        Ok(ck)
    }

    /// An empty checkpoint that keeps nothing and only sums the bytes of the
    /// arrays put into it ([`Checkpoint::measured_bytes`]): the size of a
    /// state, without copying it.
    pub fn measuring() -> Self {
        let mut ck = Self::new("", "", 0, 0.0);
        ck.store = Store::Measure(0);
        ck
    }

    /// The bytes of the arrays put into a [`Checkpoint::measuring`]
    /// checkpoint (0 for the others).
    pub fn measured_bytes(&self) -> u64 {
        match self.store {
            Store::Measure(b) => b,
            _ => 0,
        }
    }

    /// The folder of a [`Checkpoint::streaming`] checkpoint.
    pub fn stream_dir(&self) -> Option<&Path> {
        match &self.store {
            Store::Stream(s) => Some(&s.dir),
            _ => None,
        }
    }

    /// Ends a streamed checkpoint: reports the first error met while its
    /// arrays were written. Nothing to do for the others.
    ///
    /// # Errors
    /// [`CheckpointError::Io`] naming the file that could not be written,
    /// or whose fill gave another number of values than its shape.
    pub fn seal(&self) -> Result<(), CheckpointError> {
        match &self.store {
            Store::Stream(s) => match &s.error {
                Some((path, kind, message)) => Err(CheckpointError::Io {
                    path: path.clone(),
                    source: io::Error::new(*kind, message.clone()),
                }),
                None => Ok(()),
            },
            _ => Ok(()),
        }
    }

    /// This checkpoint with its arrays in memory: a copy of itself, or for
    /// a streamed one its files read back (each file's size, dtype and
    /// shape checked, as [`Checkpoint::read`] does; there is no checksum).
    ///
    /// # Errors
    /// [`CheckpointError::Truncated`], [`CheckpointError::Array`],
    /// [`CheckpointError::Io`].
    pub fn to_memory(&self) -> Result<Self, CheckpointError> {
        let Store::Stream(s) = &self.store else {
            return Ok(self.clone());
        };
        let mut ck = Self::new(&self.model, &self.scene_hash, self.step, self.time);
        ck.meta = self.meta.clone();
        for (name, (dtype, shape, bytes, hash)) in &s.entries {
            let path = s.dir.join(npy_file_name(name));
            let sum = hash.map(hash_string);
            let data = read_npy(&path, *bytes, sum.as_deref(), *dtype, shape)?;
            ck.arrays.insert(name.clone(), (shape.clone(), data));
        }
        Ok(ck)
    }

    /// This checkpoint ready for [`Checkpoint::write`]: itself, or a
    /// working copy ([`Checkpoint::streaming`]) read back into memory.
    ///
    /// # Errors
    /// Those of [`Checkpoint::to_memory`].
    pub fn into_writable(self) -> Result<Self, CheckpointError> {
        match &self.store {
            Store::Stream(s) if !s.checksums => self.to_memory(),
            _ => Ok(self),
        }
    }

    /// Starts this checkpoint over as one of `model` at `step` and `time`,
    /// keeping its arrays' buffers for the `put_*_with` calls that follow
    /// (the run loop captures its last good state again and again without
    /// allocating). Meta values are cleared; a caller must put every array
    /// again, as a model's `save` does.
    pub fn recycle(&mut self, model: &str, scene_hash: &str, step: u64, time: f64) {
        if self.model != model {
            self.model = model.to_string();
            self.arrays.clear();
        }
        if self.scene_hash != scene_hash {
            self.scene_hash = scene_hash.to_string();
        }
        self.step = step;
        self.time = time;
        self.meta.clear();
        match &mut self.store {
            Store::Memory => {}
            Store::Stream(s) => {
                s.entries.clear();
                s.error = None;
            }
            Store::Measure(b) => *b = 0,
        }
        self.source = None;
    }

    /// Adds (or replaces) an `f64` array of `shape`, filled by `fill` into
    /// an empty buffer — the one the array of that name already had, if
    /// any, so that refilling a recycled checkpoint does not allocate.
    pub fn put_f64_with(
        &mut self,
        name: &str,
        shape: Vec<usize>,
        fill: impl FnOnce(&mut ArrayFill<'_, f64>),
    ) {
        self.put_with(name, shape, fill);
    }

    /// The `u64` counterpart of [`Checkpoint::put_f64_with`].
    pub fn put_u64_with(
        &mut self,
        name: &str,
        shape: Vec<usize>,
        fill: impl FnOnce(&mut ArrayFill<'_, u64>),
    ) {
        self.put_with(name, shape, fill);
    }

    fn put_with<T: Element>(
        &mut self,
        name: &str,
        shape: Vec<usize>,
        fill: impl FnOnce(&mut ArrayFill<'_, T>),
    ) {
        match &mut self.store {
            Store::Memory => {}
            Store::Stream(s) => return s.write(name, shape, fill),
            Store::Measure(b) => {
                let n = element_count(&shape).unwrap_or(usize::MAX);
                *b = b.saturating_add((n as u64).saturating_mul(8));
                return;
            }
        }
        if let Some((s, data)) = self.arrays.get_mut(name) {
            if let Some(buf) = T::buffer(data) {
                buf.clear();
                fill(&mut ArrayFill(FillTarget::Buffer(buf)));
                debug_assert_eq!(element_count(&shape), Some(buf.len()), "`{name}`");
                *s = shape;
                return;
            }
        }
        let mut buf = Vec::new();
        fill(&mut ArrayFill(FillTarget::Buffer(&mut buf)));
        self.put(name, shape, T::wrap(buf));
    }

    /// Adds an `f64` array of `shape` (C order).
    ///
    /// `shape`'s product must equal `data.len()` and the name must match
    /// `[A-Za-z0-9_.]+` (the file is `<name>.npy`); a violation is a
    /// programming error (debug assertion) and is rejected by
    /// [`Checkpoint::write`]. A duplicate name replaces the earlier array.
    pub fn put_f64(&mut self, name: &str, shape: Vec<usize>, data: Vec<f64>) {
        self.put(name, shape, ArrayData::F64(data));
    }

    /// Adds a `u64` array; see [`Checkpoint::put_f64`].
    pub fn put_u64(&mut self, name: &str, shape: Vec<usize>, data: Vec<u64>) {
        self.put(name, shape, ArrayData::U64(data));
    }

    fn put(&mut self, name: &str, shape: Vec<usize>, data: ArrayData) {
        match &mut self.store {
            Store::Memory => {}
            Store::Stream(s) => {
                return match &data {
                    ArrayData::F64(v) => s.write(name, shape, |f| f.extend_from_slice(v)),
                    ArrayData::U64(v) => s.write(name, shape, |f| f.extend_from_slice(v)),
                };
            }
            Store::Measure(b) => {
                *b = b.saturating_add(data.len() as u64 * 8);
                return;
            }
        }
        debug_assert!(
            check_name(name).is_ok(),
            "bad checkpoint array name `{name}`"
        );
        debug_assert_eq!(
            element_count(&shape),
            Some(data.len()),
            "checkpoint array `{name}`: shape {shape:?} does not match {} values",
            data.len()
        );
        self.arrays.insert(name.to_string(), (shape, data));
    }

    /// Sets a meta value (small run-loop or model state: integers, strings).
    /// Non-finite floats would be stored as `null`.
    pub fn set_meta(&mut self, key: &str, value: Value) {
        self.meta.insert(key.to_string(), value);
    }

    /// A meta value; [`CheckpointError::Missing`] if absent.
    pub fn meta(&self, key: &str) -> Result<&Value, CheckpointError> {
        self.meta.get(key).ok_or_else(|| CheckpointError::Missing {
            what: self.describe("meta key", key),
        })
    }

    /// A meta value that must be a non-negative integer.
    pub fn meta_u64(&self, key: &str) -> Result<u64, CheckpointError> {
        let v = self.meta(key)?;
        v.as_u64().ok_or_else(|| CheckpointError::Malformed {
            what: self.describe("meta key", key),
            reason: format!("expected a non-negative integer, found {v}"),
        })
    }

    /// A meta value that must be a string.
    pub fn meta_str(&self, key: &str) -> Result<&str, CheckpointError> {
        let v = self.meta(key)?;
        v.as_str().ok_or_else(|| CheckpointError::Malformed {
            what: self.describe("meta key", key),
            reason: format!("expected a string, found {v}"),
        })
    }

    /// All meta values.
    pub fn meta_map(&self) -> &Map<String, Value> {
        &self.meta
    }

    /// Removes and returns an `f64` array, checking its dtype and (if given)
    /// its shape. On error the array stays in place.
    pub fn take_f64(
        &mut self,
        name: &str,
        shape: Option<&[usize]>,
    ) -> Result<Vec<f64>, CheckpointError> {
        match self.take(name, shape, Dtype::F64)? {
            ArrayData::F64(v) => Ok(v),
            ArrayData::U64(_) => Err(self.wrong_dtype(name, Dtype::F64, Dtype::U64)),
        }
    }

    /// Removes and returns a `u64` array; see [`Checkpoint::take_f64`].
    pub fn take_u64(
        &mut self,
        name: &str,
        shape: Option<&[usize]>,
    ) -> Result<Vec<u64>, CheckpointError> {
        match self.take(name, shape, Dtype::U64)? {
            ArrayData::U64(v) => Ok(v),
            ArrayData::F64(_) => Err(self.wrong_dtype(name, Dtype::U64, Dtype::F64)),
        }
    }

    fn take(
        &mut self,
        name: &str,
        shape: Option<&[usize]>,
        want: Dtype,
    ) -> Result<ArrayData, CheckpointError> {
        let (stored_shape, data) =
            self.arrays
                .get(name)
                .ok_or_else(|| CheckpointError::Missing {
                    what: self.describe("array", name),
                })?;
        if data.dtype() != want {
            return Err(self.wrong_dtype(name, want, data.dtype()));
        }
        if let Some(expected) = shape {
            if expected != stored_shape.as_slice() {
                return Err(CheckpointError::Malformed {
                    what: self.describe("array", name),
                    reason: format!("shape is {stored_shape:?}, expected {expected:?}"),
                });
            }
        }
        self.arrays
            .remove(name)
            .map(|(_, data)| data)
            .ok_or_else(|| CheckpointError::Missing {
                what: self.describe("array", name),
            })
    }

    fn wrong_dtype(&self, name: &str, want: Dtype, found: Dtype) -> CheckpointError {
        CheckpointError::Malformed {
            what: self.describe("array", name),
            reason: format!("stored as {}, expected {}", found.name(), want.name()),
        }
    }

    /// `checkpoint <dir>: <kind> `<name>`` for messages.
    fn describe(&self, kind: &str, name: &str) -> String {
        match &self.source {
            Some(dir) => format!("checkpoint {}: {kind} `{name}`", dir.display()),
            None => format!("checkpoint: {kind} `{name}`"),
        }
    }

    /// Shape of an array, if present.
    pub fn shape(&self, name: &str) -> Option<&[usize]> {
        self.arrays.get(name).map(|(s, _)| s.as_slice())
    }

    /// Element type of an array, if present.
    pub fn dtype(&self, name: &str) -> Option<Dtype> {
        self.arrays.get(name).map(|(_, d)| d.dtype())
    }

    /// Names of the arrays still held, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.arrays.keys().map(String::as_str)
    }

    /// Model kind, e.g. `explicit_solid<2>`.
    pub fn model(&self) -> &str {
        &self.model
    }

    /// Content hash of the scene.
    pub fn scene_hash(&self) -> &str {
        &self.scene_hash
    }

    /// Completed step count.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// Simulation time (bit-exact after a round trip).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Writes the folder `dir` atomically.
    ///
    /// Every file goes into a temporary sibling folder
    /// `.<name>.tmp-<pid>-<n>` (the manifest last), which is then renamed to
    /// `dir`; its parent is created if needed. `dir` must not exist yet
    /// ([`CheckpointError::Exists`]): the caller names each checkpoint
    /// uniquely. A kill at any moment leaves either no `dir` or a complete
    /// one, plus perhaps a stale temporary folder. Like the other outputs,
    /// files are not fsynced: the guarantee is against killed runs, not power
    /// loss.
    ///
    /// # Errors
    /// [`CheckpointError::Exists`]; [`CheckpointError::Array`] for an array
    /// whose shape does not match its data or whose name is not allowed;
    /// [`CheckpointError::Io`] for file-system errors. On error nothing is
    /// left under `dir` and the temporary folder is removed.
    pub fn write(&self, dir: &Path) -> Result<(), CheckpointError> {
        match &self.store {
            Store::Memory => {}
            Store::Stream(s) if s.checksums => return self.write_stream(s, dir),
            // Its arrays are not here, or not hashed: a working copy is read
            // back first ([`Checkpoint::to_memory`]).
            _ => {
                return Err(CheckpointError::Io {
                    path: dir.to_path_buf(),
                    source: io::Error::new(
                        io::ErrorKind::InvalidInput,
                        "a working copy or a measuring checkpoint cannot be written as a folder",
                    ),
                })
            }
        }
        let name = dir.file_name().ok_or_else(|| CheckpointError::Io {
            path: dir.to_path_buf(),
            source: io::Error::new(
                io::ErrorKind::InvalidInput,
                "checkpoint path has no folder name",
            ),
        })?;
        if dir.symlink_metadata().is_ok() {
            return Err(CheckpointError::Exists {
                dir: dir.to_path_buf(),
            });
        }
        for (array, (shape, data)) in &self.arrays {
            let file = dir.join(npy_file_name(array));
            check_name(array).map_err(|reason| CheckpointError::Array {
                file: file.clone(),
                reason,
            })?;
            if element_count(shape) != Some(data.len()) {
                return Err(CheckpointError::Array {
                    file,
                    reason: format!(
                        "shape {shape:?} does not match the {} values given",
                        data.len()
                    ),
                });
            }
        }
        let parent = dir.parent().unwrap_or(Path::new(""));
        if !parent.as_os_str().is_empty() {
            fs::create_dir_all(parent).map_err(io_err(parent))?;
        }
        let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut tmp_name = std::ffi::OsString::from(".");
        tmp_name.push(name);
        tmp_name.push(format!(".tmp-{}-{n}", std::process::id()));
        let tmp = dir.with_file_name(tmp_name);
        fs::create_dir(&tmp).map_err(io_err(&tmp))?;
        let result = self
            .write_files(dir, &tmp)
            .and_then(|()| fs::rename(&tmp, dir).map_err(io_err(dir)));
        if let Err(e) = result {
            // Best effort: the temporary folder may be partly written.
            let _ = fs::remove_dir_all(&tmp);
            if matches!(e, CheckpointError::Io { .. }) && dir.symlink_metadata().is_ok() {
                // Another writer created `dir` between the check and the rename.
                return Err(CheckpointError::Exists {
                    dir: dir.to_path_buf(),
                });
            }
            return Err(e);
        }
        Ok(())
    }

    /// [`Checkpoint::write`] of a [`Checkpoint::streaming_folder`]: its
    /// manifest into its folder, then the folder renamed to `dir`; on error
    /// the folder is removed.
    fn write_stream(&self, s: &Stream, dir: &Path) -> Result<(), CheckpointError> {
        let result = (|| {
            if dir.symlink_metadata().is_ok() {
                return Err(CheckpointError::Exists {
                    dir: dir.to_path_buf(),
                });
            }
            self.seal()?;
            let entries = s
                .entries
                .iter()
                .map(|(name, (dtype, shape, bytes, hash))| ArrayEntry {
                    name: name.clone(),
                    file: npy_file_name(name),
                    dtype: *dtype,
                    shape: shape.clone(),
                    bytes: *bytes,
                    checksum: hash.map(hash_string).unwrap_or_default(),
                })
                .collect();
            self.write_manifest(dir, &s.dir, entries)?;
            fs::rename(&s.dir, dir).map_err(io_err(dir))
        })();
        if result.is_err() {
            let _ = fs::remove_dir_all(&s.dir);
        }
        result
    }

    /// Writes the arrays and then the manifest into `tmp` (`dir` names files
    /// in messages).
    fn write_files(&self, dir: &Path, tmp: &Path) -> Result<(), CheckpointError> {
        let mut entries = Vec::with_capacity(self.arrays.len());
        for (name, (shape, data)) in &self.arrays {
            let file = npy_file_name(name);
            let bytes = encode_npy(shape, data).map_err(|e| CheckpointError::Array {
                file: dir.join(&file),
                reason: format!("cannot encode as .npy: {e}"),
            })?;
            let path = tmp.join(&file);
            fs::write(&path, &bytes).map_err(io_err(&path))?;
            entries.push(ArrayEntry {
                name: name.clone(),
                file,
                dtype: data.dtype(),
                shape: shape.clone(),
                bytes: bytes.len() as u64,
                checksum: content_hash(&bytes),
            });
        }
        self.write_manifest(dir, tmp, entries)
    }

    /// Writes the manifest of `entries` with this checkpoint's header and
    /// meta into the folder `tmp` (`dir` names it in messages).
    fn write_manifest(
        &self,
        dir: &Path,
        tmp: &Path,
        entries: Vec<ArrayEntry>,
    ) -> Result<(), CheckpointError> {
        let manifest = Manifest {
            format_version: FORMAT_VERSION,
            scene_hash: self.scene_hash.clone(),
            model: self.model.clone(),
            step: self.step,
            time: self.time,
            arrays: entries,
            meta: self.meta.clone(),
        };
        let path = tmp.join(MANIFEST_FILE);
        let mut text =
            serde_json::to_vec_pretty(&manifest).map_err(|e| CheckpointError::Manifest {
                path: dir.join(MANIFEST_FILE),
                reason: e.to_string(),
            })?;
        text.push(b'\n');
        fs::write(&path, text).map_err(io_err(&path))
    }

    /// Reads and validates only the manifest of the folder `dir` (format
    /// version and internal consistency; no scene check, no array files).
    ///
    /// # Errors
    /// [`CheckpointError::NotACheckpoint`] without `manifest.json`,
    /// [`CheckpointError::NewerVersion`], [`CheckpointError::Manifest`],
    /// [`CheckpointError::Io`].
    pub fn read_manifest(dir: &Path) -> Result<Manifest, CheckpointError> {
        let path = dir.join(MANIFEST_FILE);
        let text = match fs::read(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                return Err(CheckpointError::NotACheckpoint {
                    dir: dir.to_path_buf(),
                })
            }
            Err(e) => return Err(io_err(&path)(e)),
        };
        let bad = |reason: String| CheckpointError::Manifest {
            path: path.clone(),
            reason,
        };
        let value: Value =
            serde_json::from_slice(&text).map_err(|e| bad(format!("not valid JSON: {e}")))?;
        // The version first: a newer layout may not parse as this one.
        let version = value
            .as_object()
            .ok_or_else(|| bad("not a JSON object".to_string()))?
            .get("format_version")
            .and_then(Value::as_u64);
        if let Some(found) = version {
            if found > u64::from(FORMAT_VERSION) {
                return Err(CheckpointError::NewerVersion {
                    dir: dir.to_path_buf(),
                    found: u32::try_from(found).unwrap_or(u32::MAX),
                    supported: FORMAT_VERSION,
                });
            }
        }
        serde_json::from_value(value).map_err(|e| bad(e.to_string()))
    }

    /// Reads and fully validates the folder `dir`.
    ///
    /// Checks, in order: the manifest parses and is consistent; its
    /// `format_version` is at most [`FORMAT_VERSION`]; the scene hash equals
    /// `expect_scene_hash` when given; every listed file exists, has the
    /// listed size, the listed checksum, and parses as `.npy` with the listed
    /// dtype, C order and shape; `time` equals `time_bits`. Never panics.
    ///
    /// # Errors
    /// One [`CheckpointError`] variant per failed check (see its messages).
    pub fn read(dir: &Path, expect_scene_hash: Option<&str>) -> Result<Self, CheckpointError> {
        let manifest = Self::read_manifest(dir)?;
        if let Some(expected) = expect_scene_hash {
            if manifest.scene_hash != expected {
                return Err(CheckpointError::SceneMismatch {
                    dir: dir.to_path_buf(),
                    expected: expected.to_string(),
                    found: manifest.scene_hash,
                });
            }
        }
        let mut arrays = BTreeMap::new();
        for entry in &manifest.arrays {
            let data = read_array(dir, entry)?;
            arrays.insert(entry.name.clone(), (entry.shape.clone(), data));
        }
        Ok(Checkpoint {
            model: manifest.model,
            scene_hash: manifest.scene_hash,
            step: manifest.step,
            time: manifest.time,
            arrays,
            meta: manifest.meta,
            source: Some(dir.to_path_buf()),
            store: Store::Memory,
        })
    }
}

/// Reads one array file and checks size, checksum, dtype, order and shape.
fn read_array(dir: &Path, entry: &ArrayEntry) -> Result<ArrayData, CheckpointError> {
    read_npy(
        &dir.join(&entry.file),
        entry.bytes,
        Some(&entry.checksum),
        entry.dtype,
        &entry.shape,
    )
}

/// Reads the `.npy` file `path` and checks its size, its checksum (where
/// one is given), dtype, order and shape.
fn read_npy(
    path: &Path,
    expected_bytes: u64,
    checksum: Option<&str>,
    dtype: Dtype,
    shape: &[usize],
) -> Result<ArrayData, CheckpointError> {
    let path = path.to_path_buf();
    // The size first, so a wrong size never reads a huge file.
    let size = fs::metadata(&path).map_err(io_err(&path))?.len();
    if size != expected_bytes {
        return Err(CheckpointError::Truncated {
            file: path,
            expected: expected_bytes,
            found: size,
        });
    }
    let bytes = fs::read(&path).map_err(io_err(&path))?;
    if bytes.len() as u64 != expected_bytes {
        return Err(CheckpointError::Truncated {
            file: path,
            expected: expected_bytes,
            found: bytes.len() as u64,
        });
    }
    if let Some(expected) = checksum {
        let found = content_hash(&bytes);
        if found != expected {
            return Err(CheckpointError::Checksum {
                file: path,
                expected: expected.to_string(),
                found,
            });
        }
    }
    decode_npy(&bytes, dtype, shape).map_err(|reason| CheckpointError::Array { file: path, reason })
}

/// Encodes `data` of `shape` as a complete `.npy` file in memory.
fn encode_npy(shape: &[usize], data: &ArrayData) -> io::Result<Vec<u8>> {
    let descr = data.dtype().npy_descr();
    let mut out = Vec::with_capacity(128 + 8 * data.len());
    match data {
        ArrayData::F64(v) => {
            let mut w = super::npy::begin::<f64, _>(&mut out, descr, shape)?;
            w.extend(v.iter().copied())?;
            w.finish()?;
        }
        ArrayData::U64(v) => {
            let mut w = super::npy::begin::<u64, _>(&mut out, descr, shape)?;
            w.extend(v.iter().copied())?;
            w.finish()?;
        }
    }
    Ok(out)
}

/// Cheap structural checks of a `.npy` prefix before the full header parse:
/// magic, version, a header length inside the file and within NumPy's limit,
/// shallow bracket nesting.
fn precheck_npy(bytes: &[u8]) -> Result<(), String> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not a .npy file (no \\x93NUMPY magic)".to_string());
    }
    let (start, len) = match bytes[6] {
        1 => (10, usize::from(u16::from_le_bytes([bytes[8], bytes[9]]))),
        2 | 3 => {
            let b = bytes
                .get(8..12)
                .ok_or_else(|| "header length is cut off".to_string())?;
            (12, u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
        }
        v => return Err(format!("unsupported .npy version {v}")),
    };
    if len > NPY_MAX_HEADER {
        return Err(format!(
            "header of {len} bytes is longer than the {NPY_MAX_HEADER} allowed"
        ));
    }
    let text = bytes
        .get(start..start + len)
        .ok_or_else(|| format!("header of {len} bytes runs past the end of the file"))?;
    let mut depth = 0usize;
    for &b in text {
        match b {
            b'(' | b'[' | b'{' => {
                depth += 1;
                if depth > NPY_MAX_DEPTH {
                    return Err("header is nested too deeply".to_string());
                }
            }
            b')' | b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    Ok(())
}

/// Parses a `.npy` file held in memory, requiring `dtype`, C order and
/// `shape`, and returns its values.
fn decode_npy(bytes: &[u8], dtype: Dtype, shape: &[usize]) -> Result<ArrayData, String> {
    precheck_npy(bytes)?;
    let mut rest = bytes;
    // npyz multiplies the header's dimensions without overflow checks (a
    // panic where overflow checks are on); a hostile header must still give
    // an error, never a panic.
    let header = panic::catch_unwind(AssertUnwindSafe(|| npyz::NpyHeader::from_reader(&mut rest)))
        .map_err(|_| "header could not be parsed".to_string())?
        .map_err(|e| format!("bad .npy header: {e}"))?;
    let descr = match header.dtype() {
        npyz::DType::Plain(t) => t.to_string(),
        other => other.descr(),
    };
    if descr != dtype.npy_descr() {
        return Err(format!(
            "dtype is '{descr}', manifest says {} ('{}')",
            dtype.name(),
            dtype.npy_descr()
        ));
    }
    if header.order() != npyz::Order::C {
        return Err("array is in Fortran order, C order expected".to_string());
    }
    let same_shape = header.shape().len() == shape.len()
        && header
            .shape()
            .iter()
            .zip(shape)
            .all(|(&h, &m)| h == m as u64);
    if !same_shape {
        return Err(format!(
            "shape is {:?}, manifest says {shape:?}",
            header.shape()
        ));
    }
    let need = data_bytes(shape).ok_or_else(|| format!("shape {shape:?} is too large"))?;
    if rest.len() != need {
        return Err(format!(
            "data part has {} bytes, shape {shape:?} needs {need}",
            rest.len()
        ));
    }
    let file = npyz::NpyFile::with_header(header, rest);
    let data = match dtype {
        Dtype::F64 => file.into_vec::<f64>().map(ArrayData::F64),
        Dtype::U64 => file.into_vec::<u64>().map(ArrayData::U64),
    };
    data.map_err(|e| format!("cannot read the data: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{test_dir, test_entries as entries};
    use serde_json::json;

    const SCENE: &str = "fnv1a64:0123456789abcdef";

    fn special_f64() -> Vec<f64> {
        vec![
            0.0,
            -0.0,
            1.0,
            -2.5,
            0.1 + 0.2,
            5e-324,                                // smallest subnormal
            f64::from_bits(0x000f_ffff_ffff_ffff), // largest subnormal
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::from_bits(0x7ff8_0000_dead_beef), // quiet NaN with payload
            f64::from_bits(0xfff0_0000_0000_0001), // negative signalling NaN
            -f64::MIN_POSITIVE / 3.0,
            1.0 / 3.0,
            -1e300,
            6.02214076e23,
        ]
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// A checkpoint with one array of each kind of shape and both dtypes.
    fn sample() -> (Checkpoint, Vec<f64>) {
        let mut ck = Checkpoint::new("explicit_solid<2>", SCENE, 120, 0.1 + 0.2);
        let base = special_f64();
        let n = base.len();
        let rep = |k: usize| -> Vec<f64> { (0..k).map(|i| base[i % n]).collect() };
        ck.put_f64("empty", vec![0], vec![]);
        ck.put_f64("particles.mass", vec![n], base.clone());
        ck.put_f64("particles.x", vec![n, 3], rep(3 * n));
        ck.put_f64("particles.F", vec![n, 3, 3], rep(9 * n));
        ck.put_u64("particles.id", vec![5], vec![0, 1, u64::MAX, 1 << 53, 42]);
        ck.put_u64("u_empty", vec![0, 3], vec![]);
        ck.put_u64("cells", vec![2, 2], vec![7, 8, 9, 10]);
        ck.set_meta("rng_state", json!(u64::MAX));
        ck.set_meta("steps_since_output", json!(3));
        ck.set_meta("kind", json!("explicit"));
        ck.set_meta("nested", json!({"a": [1, 2, {"b": "c"}], "neg": -5}));
        (ck, base)
    }

    fn write_sample(tag: &str) -> (PathBuf, PathBuf) {
        let root = test_dir(tag);
        let dir = root.join("ckpt_000120");
        sample().0.write(&dir).expect("write sample");
        (root, dir)
    }

    fn load_manifest(dir: &Path) -> Value {
        serde_json::from_slice(&fs::read(dir.join(MANIFEST_FILE)).expect("read manifest"))
            .expect("parse manifest")
    }

    fn save_manifest(dir: &Path, v: &Value) {
        fs::write(
            dir.join(MANIFEST_FILE),
            serde_json::to_vec_pretty(v).expect("json"),
        )
        .expect("write manifest");
    }

    /// The manifest entry of array `name`.
    fn entry_mut<'a>(m: &'a mut Value, name: &str) -> &'a mut Value {
        m["arrays"]
            .as_array_mut()
            .expect("arrays")
            .iter_mut()
            .find(|e| e["name"] == name)
            .expect("entry")
    }

    /// Replaces an array file and "fixes" its size and checksum in the
    /// manifest, so that only the `.npy` parse can catch the damage.
    fn replace_file_fixing_manifest(dir: &Path, name: &str, bytes: &[u8]) {
        fs::write(dir.join(npy_file_name(name)), bytes).expect("write npy");
        let mut m = load_manifest(dir);
        let e = entry_mut(&mut m, name);
        e["bytes"] = json!(bytes.len());
        e["checksum"] = json!(content_hash(bytes));
        save_manifest(dir, &m);
    }

    #[test]
    fn content_hash_matches_reference_fnv1a64() {
        // Reference values of the 64-bit FNV-1a test suite.
        assert_eq!(content_hash(b""), "fnv1a64:cbf29ce484222325");
        assert_eq!(content_hash(b"a"), "fnv1a64:af63dc4c8601ec8c");
        assert_eq!(content_hash(b"foobar"), "fnv1a64:85944171f73967e8");
        assert!(is_hash(&content_hash(b"anything")));
    }

    #[test]
    fn round_trip_is_bit_exact() {
        let (root, dir) = write_sample("roundtrip");
        let (orig, base) = sample();
        let mut ck = Checkpoint::read(&dir, Some(SCENE)).expect("read");
        assert_eq!(ck.model(), "explicit_solid<2>");
        assert_eq!(ck.scene_hash(), SCENE);
        assert_eq!(ck.step(), 120);
        assert_eq!(ck.time().to_bits(), (0.1f64 + 0.2).to_bits());
        let names: Vec<&str> = ck.names().collect();
        let orig_names: Vec<&str> = orig.names().collect();
        assert_eq!(names, orig_names);
        for name in orig_names {
            assert_eq!(ck.shape(name), orig.shape(name), "{name}");
            assert_eq!(ck.dtype(name), orig.dtype(name), "{name}");
        }
        let n = base.len();
        let mass = ck.take_f64("particles.mass", Some(&[n])).expect("mass");
        assert_eq!(bits(&mass), bits(&base));
        for (name, shape) in [("particles.x", vec![n, 3]), ("particles.F", vec![n, 3, 3])] {
            let got = ck.take_f64(name, Some(&shape)).expect(name);
            let want: Vec<u64> = (0..got.len()).map(|i| base[i % n].to_bits()).collect();
            assert_eq!(got.len(), shape.iter().product::<usize>());
            assert_eq!(bits(&got), want, "{name}");
        }
        assert!(ck.take_f64("empty", Some(&[0])).expect("empty").is_empty());
        assert_eq!(
            ck.take_u64("particles.id", Some(&[5])).expect("id"),
            vec![0, 1, u64::MAX, 1 << 53, 42]
        );
        assert!(ck
            .take_u64("u_empty", Some(&[0, 3]))
            .expect("u_empty")
            .is_empty());
        assert_eq!(
            ck.take_u64("cells", None).expect("cells"),
            vec![7, 8, 9, 10]
        );
        assert_eq!(ck.names().count(), 0);
        // Meta.
        assert_eq!(ck.meta_u64("rng_state").expect("rng"), u64::MAX);
        assert_eq!(ck.meta_u64("steps_since_output").expect("steps"), 3);
        assert_eq!(ck.meta_str("kind").expect("kind"), "explicit");
        assert_eq!(ck.meta_map(), orig.meta_map());
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn header_round_trips_exactly_for_awkward_times() {
        let root = test_dir("times");
        let times = [
            0.0,
            -0.0,
            5e-324,
            0.1 + 0.2,
            1.0 / 3.0,
            1e300,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for (i, &t) in times.iter().enumerate() {
            let dir = root.join(format!("t{i}"));
            Checkpoint::new("m", "s", u64::MAX - i as u64, t)
                .write(&dir)
                .expect("write");
            let ck = Checkpoint::read(&dir, None).expect("read");
            assert_eq!(ck.time().to_bits(), t.to_bits(), "time {t:e}");
            assert_eq!(ck.step(), u64::MAX - i as u64);
            assert_eq!(ck.names().count(), 0);
            let m = load_manifest(&dir);
            assert_eq!(m["time_bits"], json!(format!("0x{:016x}", t.to_bits())));
            assert_eq!(m["time"].is_null(), !t.is_finite());
        }
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn files_are_plain_npy_and_manifest_lists_them() {
        let (root, dir) = write_sample("npy");
        let (_, base) = sample();
        let n = base.len();
        // Parse independently of `read`.
        let bytes = fs::read(dir.join("particles.x.npy")).expect("read npy");
        assert!(bytes.starts_with(b"\x93NUMPY\x01\x00"));
        let header_text = String::from_utf8_lossy(&bytes[10..]);
        assert!(header_text.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': ("));
        let npy = npyz::NpyFile::new(&bytes[..]).expect("npy header");
        assert_eq!(npy.shape(), &[n as u64, 3]);
        assert_eq!(npy.order(), npyz::Order::C);
        assert_eq!(npy.dtype().descr(), "'<f8'");
        let v: Vec<f64> = npy.into_vec().expect("npy data");
        let want: Vec<u64> = (0..3 * n).map(|i| base[i % n].to_bits()).collect();
        assert_eq!(bits(&v), want);
        // The raw data part is little-endian f64 right after the header.
        let data = &bytes[bytes.len() - 8 * 3 * n..];
        assert_eq!(data[..8], base[0].to_le_bytes());
        let ids = fs::read(dir.join("particles.id.npy")).expect("read ids");
        let npy = npyz::NpyFile::new(&ids[..]).expect("ids header");
        assert_eq!(npy.dtype().descr(), "'<u8'");
        let v: Vec<u64> = npy.into_vec().expect("ids data");
        assert_eq!(v, vec![0, 1, u64::MAX, 1 << 53, 42]);
        // Manifest: sizes and checksums of the real files, pretty JSON.
        let text = fs::read_to_string(dir.join(MANIFEST_FILE)).expect("manifest text");
        assert!(text.contains("\n  \"format_version\": 1,"), "{text}");
        let m: Manifest = serde_json::from_str(&text).expect("typed manifest");
        assert_eq!(m.format_version, FORMAT_VERSION);
        assert_eq!(m.arrays.len(), 7);
        for e in &m.arrays {
            let b = fs::read(dir.join(&e.file)).expect("file");
            assert_eq!(e.bytes, b.len() as u64, "{}", e.name);
            assert_eq!(e.checksum, content_hash(&b), "{}", e.name);
            assert_eq!(e.file, format!("{}.npy", e.name));
        }
        let mut listed: Vec<String> = m.arrays.iter().map(|e| e.file.clone()).collect();
        listed.push(MANIFEST_FILE.to_string());
        listed.sort();
        assert_eq!(entries(&dir), listed);
        // No temporary folder is left next to the checkpoint.
        assert_eq!(entries(&root), vec!["ckpt_000120".to_string()]);
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn write_refuses_an_existing_folder() {
        let (root, dir) = write_sample("exists");
        let before = fs::read(dir.join(MANIFEST_FILE)).expect("manifest");
        let other = Checkpoint::new("m", "s", 1, 1.0);
        let err = other.write(&dir).expect_err("must refuse");
        assert!(matches!(err, CheckpointError::Exists { .. }), "{err:?}");
        assert!(
            err.to_string().contains("ckpt_000120 already exists"),
            "{err}"
        );
        assert_eq!(fs::read(dir.join(MANIFEST_FILE)).expect("manifest"), before);
        // An empty existing folder is refused too.
        let empty = root.join("empty");
        fs::create_dir(&empty).expect("mkdir");
        let err = other.write(&empty).expect_err("must refuse");
        assert!(matches!(err, CheckpointError::Exists { .. }), "{err:?}");
        assert_eq!(
            entries(&root),
            vec!["ckpt_000120".to_string(), "empty".to_string()]
        );
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn write_rejects_bad_arrays_and_leaves_nothing() {
        let root = test_dir("badarrays");
        let dir = root.join("ck");
        // Bypass the debug assertions of `put_*` to reach the write checks.
        let mut ck = Checkpoint::new("m", "s", 1, 1.0);
        ck.arrays
            .insert("x".into(), (vec![2, 3], ArrayData::F64(vec![1.0; 5])));
        let err = ck.write(&dir).expect_err("shape mismatch");
        assert!(matches!(err, CheckpointError::Array { .. }), "{err:?}");
        assert!(err.to_string().contains("x.npy"), "{err}");
        assert!(err.to_string().contains("[2, 3]"), "{err}");
        let mut ck = Checkpoint::new("m", "s", 1, 1.0);
        ck.arrays
            .insert("../evil".into(), (vec![1], ArrayData::U64(vec![1])));
        let err = ck.write(&dir).expect_err("bad name");
        assert!(matches!(err, CheckpointError::Array { .. }), "{err:?}");
        assert!(
            err.to_string().contains("`../evil` is not allowed"),
            "{err}"
        );
        assert!(entries(&root).is_empty());
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn duplicate_put_replaces() {
        let mut ck = Checkpoint::new("m", "s", 1, 1.0);
        ck.put_f64("a", vec![1], vec![1.0]);
        ck.put_u64("a", vec![2], vec![3, 4]);
        assert_eq!(ck.names().collect::<Vec<_>>(), vec!["a"]);
        assert_eq!(ck.take_u64("a", Some(&[2])).expect("a"), vec![3, 4]);
    }

    #[test]
    fn read_rejects_missing_manifest() {
        let root = test_dir("nomanifest");
        let err = Checkpoint::read(&root, None).expect_err("empty folder");
        assert!(
            matches!(err, CheckpointError::NotACheckpoint { .. }),
            "{err:?}"
        );
        assert!(err.to_string().contains("no manifest.json"), "{err}");
        let err = Checkpoint::read(&root.join("nope"), None).expect_err("no folder");
        assert!(
            matches!(err, CheckpointError::NotACheckpoint { .. }),
            "{err:?}"
        );
        assert!(err.to_string().contains("nope"), "{err}");
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn read_rejects_garbage_manifest() {
        let (root, dir) = write_sample("garbage");
        fs::write(dir.join(MANIFEST_FILE), b"{\"format_version\": 1, \"arr").expect("write");
        let err = Checkpoint::read(&dir, None).expect_err("garbage");
        assert!(matches!(err, CheckpointError::Manifest { .. }), "{err:?}");
        assert!(err.to_string().contains("manifest.json"), "{err}");
        assert!(err.to_string().contains("not valid JSON"), "{err}");
        // Valid JSON, wrong schema.
        fs::write(dir.join(MANIFEST_FILE), b"{\"format_version\": 1}").expect("write");
        let err = Checkpoint::read(&dir, None).expect_err("schema");
        assert!(matches!(err, CheckpointError::Manifest { .. }), "{err:?}");
        assert!(err.to_string().contains("missing field"), "{err}");
        fs::write(dir.join(MANIFEST_FILE), b"[1, 2]").expect("write");
        let err = Checkpoint::read(&dir, None).expect_err("array");
        assert!(matches!(err, CheckpointError::Manifest { .. }), "{err:?}");
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn read_rejects_inconsistent_manifest() {
        let (root, dir) = write_sample("inconsistent");
        let good = load_manifest(&dir);
        type Edit = Box<dyn Fn(&mut Value)>;
        let cases: Vec<(&str, Edit)> = vec![
            (
                "does not match time_bits",
                Box::new(|m: &mut Value| m["time"] = json!(0.3)),
            ),
            (
                "time is null",
                Box::new(|m: &mut Value| m["time"] = Value::Null),
            ),
            (
                "time_bits",
                Box::new(|m: &mut Value| m["time_bits"] = json!("12zz")),
            ),
            (
                "expected `particles.x.npy`",
                Box::new(|m: &mut Value| entry_mut(m, "particles.x")["file"] = json!("../x.npy")),
            ),
            (
                "is not allowed",
                Box::new(|m: &mut Value| entry_mut(m, "cells")["name"] = json!("a/b")),
            ),
            (
                "impossible shape",
                Box::new(|m: &mut Value| entry_mut(m, "cells")["shape"] = json!([u64::MAX, 2])),
            ),
            (
                "checksum `crc:1`",
                Box::new(|m: &mut Value| entry_mut(m, "cells")["checksum"] = json!("crc:1")),
            ),
            (
                "listed twice",
                Box::new(|m: &mut Value| {
                    let e = entry_mut(m, "cells").clone();
                    m["arrays"].as_array_mut().expect("arrays").push(e);
                }),
            ),
            (
                "format_version 0",
                Box::new(|m: &mut Value| m["format_version"] = json!(0)),
            ),
        ];
        for (want, edit) in cases {
            let mut m = good.clone();
            edit(&mut m);
            save_manifest(&dir, &m);
            let err = Checkpoint::read(&dir, None).expect_err(want);
            assert!(
                matches!(err, CheckpointError::Manifest { .. }),
                "{want}: {err:?}"
            );
            assert!(err.to_string().contains(want), "{want}: {err}");
            assert!(err.to_string().contains("manifest.json"), "{err}");
        }
        // Time given as an integer bit pattern is accepted.
        let mut m = good.clone();
        m["time_bits"] = json!((0.1f64 + 0.2).to_bits());
        save_manifest(&dir, &m);
        assert!(Checkpoint::read(&dir, None).is_ok());
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn read_rejects_newer_version() {
        let (root, dir) = write_sample("newer");
        let mut m = load_manifest(&dir);
        m["format_version"] = json!(3);
        // A newer layout may change anything else; the version still decides.
        m["arrays"] = json!("a different layout");
        save_manifest(&dir, &m);
        let err = Checkpoint::read(&dir, None).expect_err("newer");
        assert!(
            matches!(
                err,
                CheckpointError::NewerVersion {
                    found: 3,
                    supported: 1,
                    ..
                }
            ),
            "{err:?}"
        );
        let msg = err.to_string();
        assert!(
            msg.contains("ckpt_000120 has format version 3; this build reads up to 1"),
            "{msg}"
        );
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn read_rejects_other_scene() {
        let (root, dir) = write_sample("scene");
        let other = content_hash(b"another scene");
        let err = Checkpoint::read(&dir, Some(&other)).expect_err("scene");
        assert!(
            matches!(err, CheckpointError::SceneMismatch { .. }),
            "{err:?}"
        );
        let msg = err.to_string();
        assert!(msg.contains("was written for another scene"), "{msg}");
        assert!(msg.contains(SCENE) && msg.contains(&other), "{msg}");
        assert!(Checkpoint::read(&dir, None).is_ok());
        assert!(Checkpoint::read(&dir, Some(SCENE)).is_ok());
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn read_rejects_truncated_file() {
        let (root, dir) = write_sample("truncated");
        let path = dir.join("particles.x.npy");
        let bytes = fs::read(&path).expect("read");
        let full = bytes.len() as u64;
        fs::write(&path, &bytes[..bytes.len() - 100]).expect("cut");
        let err = Checkpoint::read(&dir, None).expect_err("truncated");
        match &err {
            CheckpointError::Truncated {
                file,
                expected,
                found,
            } => {
                assert_eq!(file, &path);
                assert_eq!((*expected, *found), (full, full - 100));
            }
            other => panic!("wrong error {other:?}"),
        }
        let msg = err.to_string();
        assert!(
            msg.contains(&format!(
                "ckpt_000120: particles.x.npy is truncated: {} bytes, manifest says {full}",
                full - 100
            )),
            "{msg}"
        );
        // A longer file is caught too.
        let mut longer = bytes.clone();
        longer.extend_from_slice(&[0; 8]);
        fs::write(&path, &longer).expect("extend");
        let err = Checkpoint::read(&dir, None).expect_err("longer");
        assert!(matches!(err, CheckpointError::Truncated { .. }), "{err:?}");
        assert!(
            err.to_string()
                .contains("particles.x.npy is longer than listed"),
            "{err}"
        );
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn read_rejects_flipped_byte() {
        let (root, dir) = write_sample("flipped");
        let path = dir.join("particles.F.npy");
        let mut bytes = fs::read(&path).expect("read");
        let i = bytes.len() / 2;
        bytes[i] ^= 0x10;
        fs::write(&path, &bytes).expect("flip");
        let err = Checkpoint::read(&dir, None).expect_err("flipped");
        assert!(matches!(err, CheckpointError::Checksum { .. }), "{err:?}");
        let msg = err.to_string();
        assert!(
            msg.contains("particles.F.npy is corrupt: checksum"),
            "{msg}"
        );
        assert!(msg.contains(&content_hash(&bytes)), "{msg}");
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn read_rejects_broken_npy_with_fixed_manifest() {
        let (root, dir) = write_sample("brokennpy");
        let good = fs::read(dir.join("particles.x.npy")).expect("read");
        let header_len = 10 + usize::from(u16::from_le_bytes([good[8], good[9]]));
        let text = std::str::from_utf8(&good[10..header_len]).expect("ascii header");
        let with_header = |new_text: &str| -> Vec<u8> {
            let mut t = new_text.as_bytes().to_vec();
            t.resize(header_len - 10, b' ');
            let mut b = good[..10].to_vec();
            b.extend_from_slice(&t);
            b.extend_from_slice(&good[header_len..]);
            b
        };
        let n = special_f64().len();
        let cases: Vec<(&str, Vec<u8>)> = vec![
            ("bad .npy header", {
                let mut b = good.clone();
                b[12] = b'#'; // inside the dict literal
                b
            }),
            ("no \\x93NUMPY magic", {
                let mut b = good.clone();
                b[1] = b'X';
                b
            }),
            ("dtype is '<u8'", with_header(&text.replace("<f8", "<u8"))),
            ("dtype is '>f8'", with_header(&text.replace("<f8", ">f8"))),
            (
                "Fortran order",
                with_header(&text.replace("False", "True ")),
            ),
            (
                "shape is [3",
                with_header(&text.replace(&format!("({n}, 3, )"), &format!("(3, {n}, )"))),
            ),
            ("runs past the end", good[..40].to_vec()),
            ("data part has", good[..good.len() - 8].to_vec()),
            (
                "nested too deeply",
                with_header("{'descr': [[[[['<f8']]]]]}"),
            ),
            // Dimensions whose products overflow u64 (npyz's unchecked
            // multiplication): an error either way, never a panic.
            (
                "particles.x.npy: ",
                with_header(&text.replace(
                    &format!("({n}, 3, )"),
                    "(0, 1099511627776, 1099511627776, )",
                )),
            ),
            ("unsupported .npy version 9", {
                let mut b = good.clone();
                b[6] = 9;
                b
            }),
        ];
        for (want, bytes) in cases {
            replace_file_fixing_manifest(&dir, "particles.x", &bytes);
            let err = Checkpoint::read(&dir, None).expect_err(want);
            assert!(
                matches!(err, CheckpointError::Array { .. }),
                "{want}: {err:?}"
            );
            let msg = err.to_string();
            assert!(
                msg.contains("ckpt_000120: array file particles.x.npy: "),
                "{msg}"
            );
            assert!(msg.contains(want), "{want}: {msg}");
        }
        // The untouched file reads again.
        replace_file_fixing_manifest(&dir, "particles.x", &good);
        assert!(Checkpoint::read(&dir, None).is_ok());
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn read_rejects_missing_array_file() {
        let (root, dir) = write_sample("missingfile");
        let path = dir.join("particles.id.npy");
        fs::remove_file(&path).expect("remove");
        let err = Checkpoint::read(&dir, None).expect_err("missing file");
        match &err {
            CheckpointError::Io { path: p, source } => {
                assert_eq!(p, &path);
                assert_eq!(source.kind(), io::ErrorKind::NotFound);
            }
            other => panic!("wrong error {other:?}"),
        }
        assert!(err.to_string().contains("particles.id.npy"), "{err}");
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn read_never_panics_on_corrupted_input() {
        // A small checkpoint keeps the number of file operations down.
        let root = test_dir("fuzz");
        let dir = root.join("ck");
        let mut ck = Checkpoint::new("m", SCENE, 7, 0.5);
        ck.put_u64("cells", vec![2, 2], vec![7, 8, 9, 10]);
        ck.set_meta("k", json!(1));
        ck.write(&dir).expect("write");
        let good_manifest = fs::read(dir.join(MANIFEST_FILE)).expect("manifest");
        // Every prefix of the manifest (short of its closing brace) and
        // single-byte changes of it.
        for cut in 0..good_manifest.trim_ascii_end().len() {
            fs::write(dir.join(MANIFEST_FILE), &good_manifest[..cut]).expect("write");
            assert!(
                Checkpoint::read(&dir, None).is_err(),
                "manifest cut at {cut}"
            );
        }
        for i in (0..good_manifest.len()).step_by(3) {
            let mut m = good_manifest.clone();
            m[i] ^= 0x5a;
            fs::write(dir.join(MANIFEST_FILE), &m).expect("write");
            let _ = Checkpoint::read(&dir, None);
        }
        fs::write(dir.join(MANIFEST_FILE), &good_manifest).expect("restore");
        // Every byte of an array file changed or cut, with the manifest fixed
        // so that the .npy parser sees the damage.
        let good = fs::read(dir.join("cells.npy")).expect("npy");
        let mut accepted = 0;
        for i in 0..good.len() {
            for mask in [0x01u8, 0x20, 0xff] {
                let mut b = good.clone();
                b[i] ^= mask;
                replace_file_fixing_manifest(&dir, "cells", &b);
                if let Ok(mut ck) = Checkpoint::read(&dir, None) {
                    // Only data bytes or harmless header padding may change.
                    accepted += 1;
                    assert_eq!(ck.take_u64("cells", Some(&[2, 2])).expect("cells").len(), 4);
                }
            }
            replace_file_fixing_manifest(&dir, "cells", &good[..i]);
            assert!(Checkpoint::read(&dir, None).is_err(), "npy cut at {i}");
        }
        // The 32 data bytes x 3 masks decode to other numbers; nothing else
        // may pass, except changed padding bytes that stay whitespace.
        assert!(accepted >= 32 * 3, "{accepted}");
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn take_checks_dtype_shape_and_presence() {
        let (mut ck, base) = sample();
        let n = base.len();
        let err = ck.take_u64("particles.x", None).expect_err("dtype");
        assert!(matches!(err, CheckpointError::Malformed { .. }), "{err:?}");
        assert_eq!(
            err.to_string(),
            "checkpoint: array `particles.x`: stored as f64, expected u64"
        );
        let err = ck
            .take_f64("particles.x", Some(&[n, 2]))
            .expect_err("shape");
        assert!(matches!(err, CheckpointError::Malformed { .. }), "{err:?}");
        assert!(
            err.to_string()
                .contains(&format!("shape is [{n}, 3], expected [{n}, 2]")),
            "{err}"
        );
        let err = ck.take_f64("particles.v", None).expect_err("missing");
        assert!(matches!(err, CheckpointError::Missing { .. }), "{err:?}");
        assert_eq!(
            err.to_string(),
            "checkpoint: array `particles.v` is missing"
        );
        // Failed takes leave the array in place.
        assert_eq!(ck.shape("particles.x"), Some(&[n, 3][..]));
        assert_eq!(
            ck.take_f64("particles.x", Some(&[n, 3])).expect("x").len(),
            3 * n
        );
        assert_eq!(ck.shape("particles.x"), None);
        let err = ck.take_f64("particles.x", None).expect_err("taken");
        assert!(matches!(err, CheckpointError::Missing { .. }), "{err:?}");
        // Meta.
        let err = ck.meta_u64("kind").expect_err("string");
        assert!(matches!(err, CheckpointError::Malformed { .. }), "{err:?}");
        assert!(err.to_string().contains("meta key `kind`"), "{err}");
        let err = ck.meta_u64("nested").expect_err("object");
        assert!(matches!(err, CheckpointError::Malformed { .. }), "{err:?}");
        let err = ck.meta("absent").expect_err("absent");
        assert!(matches!(err, CheckpointError::Missing { .. }), "{err:?}");
        assert!(
            err.to_string().contains("meta key `absent` is missing"),
            "{err}"
        );
        let err = ck.meta_str("rng_state").expect_err("number");
        assert!(matches!(err, CheckpointError::Malformed { .. }), "{err:?}");
    }

    #[test]
    fn errors_after_read_name_the_folder() {
        let (root, dir) = write_sample("named");
        let mut ck = Checkpoint::read(&dir, Some(SCENE)).expect("read");
        let err = ck.take_u64("particles.x", None).expect_err("dtype");
        assert_eq!(
            err.to_string(),
            format!(
                "checkpoint {}: array `particles.x`: stored as f64, expected u64",
                dir.display()
            )
        );
        fs::remove_dir_all(&root).expect("cleanup");
    }

    /// The sample's arrays and meta put into `ck`, half of them through
    /// the fill closures the run loop's capture uses.
    fn put_sample(ck: &mut Checkpoint) {
        let (mem, _) = sample();
        for (name, (shape, data)) in &mem.arrays {
            match data {
                ArrayData::F64(v) if name.contains('.') => {
                    ck.put_f64_with(name, shape.clone(), |f| {
                        for x in v {
                            f.extend([*x]);
                        }
                    })
                }
                ArrayData::U64(v) if name.contains('.') => {
                    ck.put_u64_with(name, shape.clone(), |f| f.extend(v))
                }
                _ => ck.put(name, shape.clone(), data.clone()),
            }
        }
        for (k, v) in mem.meta_map() {
            ck.set_meta(k, v.clone());
        }
    }

    #[test]
    fn a_streamed_checkpoint_is_the_written_one_file_for_file() {
        let root = test_dir("streamed");
        let (written, stream_dir) = (root.join("written"), root.join("streamed"));
        sample().0.write(&written).expect("write");
        let (model, step, time) = ("explicit_solid<2>", 120, 0.1 + 0.2);
        let mut ck = Checkpoint::streaming(&stream_dir, model, SCENE, step, time).expect("open");
        put_sample(&mut ck);
        ck.seal().expect("seal");
        assert!(
            ck.arrays.is_empty(),
            "a streamed checkpoint keeps no arrays"
        );
        // The same array files, byte for byte; no manifest.
        let mut files = entries(&written);
        files.retain(|f| f != MANIFEST_FILE);
        assert_eq!(files, entries(&stream_dir));
        for f in &files {
            let a = fs::read(written.join(f)).expect("written file");
            let b = fs::read(stream_dir.join(f)).expect("streamed file");
            assert!(a == b, "{f} differs");
        }
        // Read back, it equals the sample bit for bit.
        let back = ck.to_memory().expect("read back");
        let (orig, _) = sample();
        assert_eq!(back.arrays.len(), orig.arrays.len());
        assert_eq!(back.meta_map(), orig.meta_map());
        assert_eq!(
            (back.step(), back.time(), back.model()),
            (step, time, model)
        );
        for (name, (shape, data)) in &orig.arrays {
            let (s2, d2) = &back.arrays[name];
            assert_eq!(shape, s2, "{name}");
            match (data, d2) {
                (ArrayData::F64(a), ArrayData::F64(b)) => assert_eq!(bits(a), bits(b), "{name}"),
                (a, b) => assert_eq!(a, b, "{name}"),
            }
        }
        // Recycled and put again, it reads back as the new state.
        ck.recycle(model, SCENE, step + 1, time);
        put_sample(&mut ck);
        ck.seal().expect("seal again");
        assert_eq!(ck.to_memory().expect("read").step(), step + 1);
        // Files are overwritten in place: a shorter array leaves no tail.
        ck.recycle(model, SCENE, step + 2, time);
        ck.put_f64_with("particles.mass", vec![2], |f| {
            f.extend_from_slice(&[1.5, -2.0])
        });
        ck.seal().expect("seal a shorter state");
        let mut back = ck.to_memory().expect("read the shorter state");
        assert_eq!(
            back.take_f64("particles.mass", Some(&[2])).expect("mass"),
            [1.5, -2.0]
        );
        assert!(back.names().next().is_none(), "only the array put last");
        // It cannot be written as a folder of its own.
        assert!(ck.write(&root.join("again")).is_err());
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn a_streamed_checkpoint_folder_is_the_written_one_byte_for_byte() {
        let root = test_dir("streamed_folder");
        let written = root.join("written");
        sample().0.write(&written).expect("write");
        let (tmp, dir) = (root.join(".tmp"), root.join("streamed"));
        let mut ck = Checkpoint::streaming_folder(&tmp, "explicit_solid<2>", SCENE, 120, 0.1 + 0.2)
            .expect("open");
        put_sample(&mut ck);
        ck.write(&dir).expect("write the streamed folder");
        assert!(!tmp.exists(), "renamed into place");
        assert_eq!(entries(&written), entries(&dir));
        for f in entries(&written) {
            let a = fs::read(written.join(&f)).expect("a");
            let b = fs::read(dir.join(&f)).expect("b");
            assert!(a == b, "{f} differs");
        }
        Checkpoint::read(&dir, Some(SCENE)).expect("reads and checks");
        // Onto an existing folder: refused, and the temporary folder goes.
        let mut again = Checkpoint::streaming_folder(&tmp, "m", SCENE, 1, 1.0).expect("open again");
        put_sample(&mut again);
        assert!(matches!(
            again.write(&dir),
            Err(CheckpointError::Exists { .. })
        ));
        assert!(!tmp.exists());
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn a_streamed_checkpoint_reports_the_file_it_could_not_write() {
        let root = test_dir("streamed_error");
        let dir = root.join("state");
        let mut ck = Checkpoint::streaming(&dir, "m", SCENE, 1, 1.0).expect("open");
        fs::remove_dir_all(&dir).expect("remove");
        ck.put_f64_with("a.b", vec![2], |f| f.extend_from_slice(&[1.0, 2.0]));
        match ck.seal() {
            Err(CheckpointError::Io { path, .. }) => assert_eq!(path, dir.join("a.b.npy")),
            other => panic!("{other:?}"),
        }
        // A file cut short is found on reading back.
        fs::create_dir_all(&dir).expect("mkdir");
        ck.recycle("m", SCENE, 2, 2.0);
        ck.put_f64_with("a.b", vec![2], |f| f.extend_from_slice(&[1.0, 2.0]));
        ck.seal().expect("seal");
        let file = dir.join("a.b.npy");
        let bytes = fs::read(&file).expect("read");
        fs::write(&file, &bytes[..bytes.len() - 8]).expect("cut");
        assert!(matches!(
            ck.to_memory(),
            Err(CheckpointError::Truncated { .. })
        ));
        // A fill that gives fewer values than its shape is an error too.
        ck.recycle("m", SCENE, 3, 3.0);
        ck.put_f64_with("short", vec![3], |f| f.extend_from_slice(&[1.0]));
        let e = ck.seal().expect_err("short array");
        assert!(e.to_string().contains("does not match the 1 values"), "{e}");
        fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn a_measuring_checkpoint_counts_bytes_and_keeps_nothing() {
        let mut ck = Checkpoint::measuring();
        put_sample(&mut ck);
        let (orig, _) = sample();
        let expected: usize = orig.arrays.values().map(|(_, d)| d.len() * 8).sum();
        assert_eq!(ck.measured_bytes(), expected as u64);
        assert!(ck.arrays.is_empty());
        ck.recycle("m", SCENE, 0, 0.0);
        assert_eq!(ck.measured_bytes(), 0);
    }
}
