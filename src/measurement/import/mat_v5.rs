//! Reader for MATLAB level-5 MAT files (`save -v6` / `-v7`), after MathWorks' "MAT-File Format".
//!
//! Only what a numeric workflow needs is decoded: every top-level real 2-D numeric or logical
//! array, converted to `f64`, column-major. Other variables (char, cell, struct, object, sparse,
//! complex, N-D, ...) are listed in [`MatFile::skipped`] with the reason.
//!
//! The reader is meant for untrusted input: it never panics on malformed bytes, checks every
//! length against the bytes present, and caps the data inflated from `miCOMPRESSED` elements at
//! 512 MiB for the whole file, reading each zlib stream in bounded chunks. Errors name the byte
//! offset (in the file, or in the inflated data of a compressed element) and what was wrong.

use std::fmt;
use std::io::Read;

/// Length of the fixed file header.
const HEADER_LEN: usize = 128;
/// Cap on the bytes inflated from all `miCOMPRESSED` elements of one file.
const MAX_INFLATED: usize = 512 << 20;
/// Size of the chunks the zlib stream is read in.
const INFLATE_CHUNK: usize = 64 << 10;
/// HDF5 format signature (MAT v7.3 files are HDF5 files with a 512-byte user block).
const HDF5_SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MI_UTF8: u32 = 16;

/// Array-flags bit (in the second byte) marking a complex array.
const FLAG_COMPLEX: u32 = 0x0800;

/// One numeric array of a MAT file.
#[derive(Debug, Clone, PartialEq)]
pub struct MatArray {
    /// Variable name.
    pub name: String,
    /// Number of rows.
    pub rows: usize,
    /// Number of columns.
    pub cols: usize,
    /// Values in column-major order, as MATLAB stores them: (`r`, `c`) is `values[c * rows + r]`.
    pub values: Vec<f64>,
}

impl MatArray {
    /// Value at zero-based (`row`, `col`).
    ///
    /// # Panics
    /// If `row >= self.rows` or `col >= self.cols` (a caller bug, like slice indexing), or if `values` holds
    /// fewer than `rows * cols` values (never for arrays returned by [`read`]).
    pub fn get(&self, row: usize, col: usize) -> f64 {
        let index = col.checked_mul(self.rows).and_then(|i| i.checked_add(row));
        match index
            .filter(|_| row < self.rows && col < self.cols)
            .and_then(|i| self.values.get(i))
        {
            Some(v) => *v,
            None => panic!(
                "MatArray `{}` is {}x{} with {} values, index ({row}, {col}) is out of range",
                self.name,
                self.rows,
                self.cols,
                self.values.len()
            ),
        }
    }
}

/// The decoded contents of a MAT file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MatFile {
    /// Every top-level real 2-D numeric or logical array, in file order.
    pub arrays: Vec<MatArray>,
    /// Top-level variables not decoded: (name, why).
    pub skipped: Vec<(String, String)>,
}

impl MatFile {
    /// The first decoded array called `name`, if any.
    pub fn array(&self, name: &str) -> Option<&MatArray> {
        self.arrays.iter().find(|a| a.name == name)
    }
}

/// A position in the input, for error messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pos {
    /// Byte offset: in the file, or in the inflated data when `zlib_at` is set.
    pub offset: usize,
    /// File offset of the `miCOMPRESSED` element whose inflated data `offset` refers to.
    pub zlib_at: Option<usize>,
}

impl fmt::Display for Pos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.zlib_at {
            None => write!(f, "byte {}", self.offset),
            Some(z) => write!(
                f,
                "byte {} of the data inflated from the miCOMPRESSED element at byte {z}",
                self.offset
            ),
        }
    }
}

/// Why a MAT file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum MatError {
    /// Not a level-5 MAT file: too short, v4, HDF5-based v7.3, or an unknown version.
    #[error("not a MAT v5 file (header {0})")]
    NotV5(String),
    /// Fewer than 8 bytes left where a data element tag should start.
    #[error("{at}: data element tag needs 8 bytes, only {remain} remain")]
    ShortTag {
        /// Where the tag should start.
        at: Pos,
        /// Bytes left in the enclosing file, stream or element.
        remain: usize,
    },
    /// A data element declares more bytes than its container has left.
    #[error("{at}: data element of type {ty} claims {claimed} bytes, only {remain} remain after its tag")]
    Overrun {
        /// Where the element's tag starts.
        at: Pos,
        /// The element's data type.
        ty: u32,
        /// The size its tag declares.
        claimed: usize,
        /// Bytes left after its tag in the enclosing file, stream or element.
        remain: usize,
    },
    /// The zlib stream of a `miCOMPRESSED` element is corrupt or truncated.
    #[error("{at}: zlib stream of miCOMPRESSED element is corrupt or truncated ({detail})")]
    Zlib {
        /// Where the compressed element's tag starts.
        at: Pos,
        /// What the decoder reported.
        detail: String,
    },
    /// Inflating would exceed the cap on inflated data per file.
    #[error("{at}: miCOMPRESSED data inflates beyond the limit of {limit} bytes per file")]
    TooLarge {
        /// Where the compressed element's tag starts.
        at: Pos,
        /// The cap, in bytes.
        limit: usize,
    },
    /// Any other structural problem.
    #[error("{at}: {what}")]
    Malformed {
        /// Where the offending element starts.
        at: Pos,
        /// What was wrong.
        what: String,
    },
}

/// Reads every top-level numeric 2-D real array; names of skipped variables (char, cell, struct, sparse, complex,
/// >2-D) are returned too.
pub fn read(bytes: &[u8]) -> Result<MatFile, MatError> {
    read_limited(bytes, MAX_INFLATED)
}

/// [`read`] with a given cap on the bytes inflated from all compressed elements.
fn read_limited(bytes: &[u8], limit: usize) -> Result<MatFile, MatError> {
    let order = parse_header(bytes)?;
    let mut file = MatFile::default();
    let mut budget = Budget { left: limit, limit };
    let mut top = Elements {
        buf: bytes,
        pos: HEADER_LEN,
        end: bytes.len(),
        order,
        zlib_at: None,
    };
    while let Some(el) = top.next()? {
        match el.ty {
            MI_COMPRESSED => read_compressed(&el, order, &mut budget, &mut file)?,
            MI_MATRIX => file.add(parse_matrix(&top, &el)?),
            ty => {
                return Err(top.malformed(
                    el.at,
                    format!("top-level data element of type {ty}, expected miMATRIX (14) or miCOMPRESSED (15)"),
                ));
            }
        }
    }
    Ok(file)
}

impl MatFile {
    fn add(&mut self, var: Var) {
        match var {
            Var::Array(a) => self.arrays.push(a),
            Var::Skipped(name, why) => self.skipped.push((name, why.into_owned())),
        }
    }
}

/// Byte order of the file's numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Order {
    Little,
    Big,
}

impl Order {
    fn u16(self, b: [u8; 2]) -> u16 {
        match self {
            Order::Little => u16::from_le_bytes(b),
            Order::Big => u16::from_be_bytes(b),
        }
    }

    fn u32(self, b: [u8; 4]) -> u32 {
        match self {
            Order::Little => u32::from_le_bytes(b),
            Order::Big => u32::from_be_bytes(b),
        }
    }
}

/// `N` bytes of `buf` from `at`, or `None` if they are not all there.
fn take<const N: usize>(buf: &[u8], at: usize) -> Option<[u8; N]> {
    let src = buf.get(at..at.checked_add(N)?)?;
    let mut out = [0u8; N];
    out.iter_mut().zip(src).for_each(|(d, s)| *d = *s);
    Some(out)
}

/// Checks the 128-byte header and returns the file's byte order.
fn parse_header(bytes: &[u8]) -> Result<Order, MatError> {
    let is_hdf5 = |at: usize| bytes.get(at..at + HDF5_SIGNATURE.len()) == Some(&HDF5_SIGNATURE[..]);
    if bytes.starts_with(b"MATLAB 7.3") || is_hdf5(0) || is_hdf5(512) {
        return Err(MatError::NotV5(format!(
            "text \"{}\"{}): this is the HDF5-based MAT v7.3 format, which this reader does not support; \
             re-save it in MATLAB with save(..., '-v7') or export the variables to CSV",
            header_text(bytes),
            if is_hdf5(512) {
                " and HDF5 signature at byte 512"
            } else {
                ""
            }
        )));
    }
    let (Some(version), Some(endian)) = (take::<2>(bytes, 124), take::<2>(bytes, 126)) else {
        return Err(MatError::NotV5(format!(
            "needs {HEADER_LEN} bytes, the input has only {}",
            bytes.len()
        )));
    };
    let order = match &endian {
        b"IM" => Order::Little,
        b"MI" => Order::Big,
        _ => {
            return Err(MatError::NotV5(format!(
                "has no \"IM\"/\"MI\" endian indicator at bytes 126-127, found {:#04x} {:#04x}; \
                 MAT v4 files and other formats are not supported",
                endian[0], endian[1]
            )));
        }
    };
    match order.u16(version) {
        0x0100 => Ok(order),
        v => Err(MatError::NotV5(format!(
            "version {v:#06x} at bytes 124-125, expected 0x0100 (level 5)"
        ))),
    }
}

/// The printable start of the header text, for messages.
fn header_text(bytes: &[u8]) -> String {
    let text = bytes.get(..bytes.len().min(116)).unwrap_or_default();
    let end = text
        .iter()
        .position(|&b| b == 0 || !(b == b' ' || b.is_ascii_graphic()))
        .unwrap_or(text.len());
    String::from_utf8_lossy(text.get(..end).unwrap_or_default())
        .trim_end()
        .to_string()
}

/// One data element: type, position of its tag, and its data (padding excluded).
struct Element<'a> {
    ty: u32,
    at: usize,
    data_at: usize,
    data: &'a [u8],
}

/// Iterates the data elements in `buf[pos..end]`.
struct Elements<'a> {
    buf: &'a [u8],
    pos: usize,
    end: usize,
    order: Order,
    zlib_at: Option<usize>,
}

impl<'a> Elements<'a> {
    fn at(&self, offset: usize) -> Pos {
        Pos {
            offset,
            zlib_at: self.zlib_at,
        }
    }

    fn malformed(&self, offset: usize, what: String) -> MatError {
        MatError::Malformed {
            at: self.at(offset),
            what,
        }
    }

    /// The elements inside `el`'s data.
    fn inside(&self, el: &Element<'a>) -> Elements<'a> {
        Elements {
            pos: el.data_at,
            end: el.data_at + el.data.len(),
            ..*self
        }
    }

    /// The next element, `None` at the end, or an error if its tag or data is cut off.
    fn next(&mut self) -> Result<Option<Element<'a>>, MatError> {
        let at = self.pos;
        if at >= self.end {
            return Ok(None);
        }
        let (ty, len, small) = self.tag(at)?;
        let data_at = if small { at + 4 } else { at + 8 };
        let room = self.end - data_at;
        let data = match self.buf.get(data_at..data_at.saturating_add(len)) {
            Some(d) if len <= room => d,
            _ => {
                return Err(MatError::Overrun {
                    at: self.at(at),
                    ty,
                    claimed: len,
                    remain: room,
                });
            }
        };
        self.pos = if small {
            at + 8
        } else if ty == MI_COMPRESSED {
            // MATLAB does not pad compressed elements.
            data_at + len
        } else {
            // Padding to 8 bytes; tolerate its absence at the very end of the container.
            (data_at + len.next_multiple_of(8)).min(self.end)
        };
        Ok(Some(Element { ty, at, data_at, data }))
    }

    /// Decodes the tag at `at` (before `self.end`): type, data length, and whether it is a small element.
    fn tag(&self, at: usize) -> Result<(u32, usize, bool), MatError> {
        let remain = self.end - at;
        let word = |o: usize| take::<4>(self.buf, at + o).map(|b| self.order.u32(b));
        let (Some(w0), Some(w1), true) = (word(0), word(4), remain >= 8) else {
            return Err(MatError::ShortTag {
                at: self.at(at),
                remain,
            });
        };
        if w0 >> 16 == 0 {
            return Ok((w0, w1 as usize, false));
        }
        // Small data element: size in the upper 16 bits, type in the lower, data in the tag's last 4 bytes.
        let (ty, len) = (w0 & 0xffff, (w0 >> 16) as usize);
        if len > 4 {
            let what = format!("small data element of type {ty} claims {len} bytes, at most 4 fit in its tag");
            return Err(self.malformed(at, what));
        }
        Ok((ty, len, true))
    }

    /// The next element, which must be there and have one of the types `want`.
    fn expect(&mut self, parent: usize, want: &[u32], what: &str) -> Result<Element<'a>, MatError> {
        match self.next()? {
            Some(el) if want.contains(&el.ty) => Ok(el),
            Some(el) => Err(self.malformed(
                el.at,
                format!("{what}: expected data type {want:?}, found type {}", el.ty),
            )),
            None => Err(self.malformed(parent, format!("miMATRIX element ends before its {what}"))),
        }
    }
}

/// Remaining allowance of inflated bytes.
struct Budget {
    left: usize,
    limit: usize,
}

/// Inflates a `miCOMPRESSED` element and reads the matrices in it.
fn read_compressed(el: &Element, order: Order, budget: &mut Budget, file: &mut MatFile) -> Result<(), MatError> {
    let inflated = inflate(el, budget)?;
    let mut inner = Elements {
        buf: &inflated,
        pos: 0,
        end: inflated.len(),
        order,
        zlib_at: Some(el.at),
    };
    while let Some(sub) = inner.next()? {
        match sub.ty {
            MI_MATRIX => file.add(parse_matrix(&inner, &sub)?),
            ty => {
                return Err(inner.malformed(
                    sub.at,
                    format!("compressed data element of type {ty}, expected miMATRIX (14)"),
                ));
            }
        }
    }
    Ok(())
}

/// Inflates the zlib stream of `el` in bounded chunks, charging `budget`.
fn inflate(el: &Element, budget: &mut Budget) -> Result<Vec<u8>, MatError> {
    let at = Pos {
        offset: el.at,
        zlib_at: None,
    };
    let mut decoder = flate2::read::ZlibDecoder::new(el.data);
    let mut out = Vec::new();
    let mut chunk = vec![0u8; INFLATE_CHUNK];
    loop {
        let n = match decoder.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => {
                return Err(MatError::Zlib {
                    at,
                    detail: e.to_string(),
                });
            }
        };
        let got = chunk.get(..n).unwrap_or_default();
        if got.len() > budget.left - out.len() {
            return Err(MatError::TooLarge {
                at,
                limit: budget.limit,
            });
        }
        out.extend_from_slice(got);
    }
    budget.left -= out.len();
    Ok(out)
}

/// A top-level variable: decoded, or skipped with the reason.
enum Var {
    Array(MatArray),
    Skipped(String, std::borrow::Cow<'static, str>),
}

/// Decodes one `miMATRIX` element whose data lies in `outer`'s buffer.
fn parse_matrix(outer: &Elements, el: &Element) -> Result<Var, MatError> {
    if el.data.is_empty() {
        return Ok(Var::Skipped(String::new(), "empty miMATRIX element".into()));
    }
    let mut sub = outer.inside(el);
    let flags_el = sub.expect(el.at, &[MI_UINT32], "array flags")?;
    let flags = take::<4>(flags_el.data, 0).map(|b| outer.order.u32(b)).ok_or_else(|| {
        outer.malformed(
            flags_el.at,
            format!("array flags need 8 bytes, found {}", flags_el.data.len()),
        )
    })?;
    let dims_el = sub.expect(el.at, &[MI_INT32], "dimensions")?;
    let dims = parse_dims(&sub, &dims_el)?;
    let name_el = sub.expect(el.at, &[MI_INT8, MI_UINT8, MI_UTF8], "array name")?;
    let name = String::from_utf8_lossy(name_el.data).into_owned();
    let (rows, cols) = match shape(flags, &dims, &name) {
        Ok(rc) => rc,
        Err(why) => return Ok(Var::Skipped(name, why)),
    };
    let count = rows
        .checked_mul(cols)
        .ok_or_else(|| outer.malformed(el.at, format!("dimensions {rows} x {cols} overflow")))?;
    let real = sub.expect(el.at, &NUMERIC_TYPES, "real part")?;
    let values = decode_values(&sub, &real, count, (rows, cols))?;
    Ok(Var::Array(MatArray {
        name,
        rows,
        cols,
        values,
    }))
}

/// Storage types a numeric real part may use.
const NUMERIC_TYPES: [u32; 10] = [
    MI_INT8, MI_UINT8, MI_INT16, MI_UINT16, MI_INT32, MI_UINT32, MI_SINGLE, MI_DOUBLE, MI_INT64, MI_UINT64,
];

/// The dimensions of an array, each non-negative.
fn parse_dims(sub: &Elements, el: &Element) -> Result<Vec<usize>, MatError> {
    if !el.data.len().is_multiple_of(4) || el.data.len() < 8 {
        return Err(sub.malformed(
            el.at,
            format!(
                "dimensions take {} bytes, expected 4 per dimension, at least 2",
                el.data.len()
            ),
        ));
    }
    el.data
        .chunks_exact(4)
        .map(|c| {
            let d = sub.order.u32(take::<4>(c, 0).unwrap_or_default()) as i32;
            usize::try_from(d).map_err(|_| sub.malformed(el.at, format!("negative dimension {d}")))
        })
        .collect()
}

/// Why an array of this class is not decoded, or `None` for a real numeric or logical class.
fn class_skip_reason(class: u32, complex: bool) -> Option<&'static str> {
    Some(match class {
        6..=15 if complex => "complex",
        6..=15 => return None,
        1 => "cell array",
        2 => "struct",
        3 => "object",
        4 => "char array",
        5 => "sparse matrix",
        16 => "function handle",
        17 => "opaque object (string, table, datetime, ...)",
        _ => "unknown array class",
    })
}

/// Rows and columns of a decodable array, or why it is skipped (an array of more dimensions:
/// how many, and their sizes).
fn shape(flags: u32, dims: &[usize], name: &str) -> Result<(usize, usize), std::borrow::Cow<'static, str>> {
    if let Some(why) = class_skip_reason(flags & 0xff, flags & FLAG_COMPLEX != 0) {
        return Err(why.into());
    }
    // MATLAB drops trailing singleton dimensions; other writers may keep them.
    if dims.iter().skip(2).any(|&d| d != 1) {
        let sizes: Vec<String> = dims.iter().map(ToString::to_string).collect();
        return Err(format!("{} dimensions ({})", dims.len(), sizes.join(" x ")).into());
    }
    if name.is_empty() {
        return Err("unnamed array (subsystem data)".into());
    }
    match dims {
        [rows, cols, ..] => Ok((*rows, *cols)),
        _ => Err("fewer than 2 dimensions".into()),
    }
}

/// Bytes per value of a numeric storage type.
fn storage_width(ty: u32) -> Option<usize> {
    match ty {
        MI_INT8 | MI_UINT8 => Some(1),
        MI_INT16 | MI_UINT16 => Some(2),
        MI_INT32 | MI_UINT32 | MI_SINGLE => Some(4),
        MI_DOUBLE | MI_INT64 | MI_UINT64 => Some(8),
        _ => None,
    }
}

/// Converts the real part `real` of a `rows` x `cols` array to `f64`, checking it holds exactly `count` values.
fn decode_values(
    sub: &Elements,
    real: &Element,
    count: usize,
    (rows, cols): (usize, usize),
) -> Result<Vec<f64>, MatError> {
    let (ty, len) = (real.ty, real.data.len());
    let width =
        storage_width(ty).ok_or_else(|| sub.malformed(real.at, format!("real part has non-numeric type {ty}")))?;
    let what = if !len.is_multiple_of(width) {
        format!("real part of type {ty} has {len} bytes, not a multiple of {width}")
    } else if len / width != count {
        format!(
            "{rows} x {cols} array needs {count} values, its real part (type {ty}) holds {}",
            len / width
        )
    } else {
        return decode(ty, real.data, sub.order)
            .ok_or_else(|| sub.malformed(real.at, format!("real part has non-numeric type {ty}")));
    };
    Err(sub.malformed(real.at, what))
}

/// Values of storage type `ty` in `data` (whose length is a multiple of the type's width) as `f64`.
fn decode(ty: u32, data: &[u8], order: Order) -> Option<Vec<f64>> {
    Some(match ty {
        MI_INT8 => conv(data, order, |b: [u8; 1]| f64::from(i8::from_le_bytes(b))),
        MI_UINT8 => conv(data, order, |b: [u8; 1]| f64::from(u8::from_le_bytes(b))),
        MI_INT16 => conv(data, order, |b| f64::from(i16::from_le_bytes(b))),
        MI_UINT16 => conv(data, order, |b| f64::from(u16::from_le_bytes(b))),
        MI_INT32 => conv(data, order, |b| f64::from(i32::from_le_bytes(b))),
        MI_UINT32 => conv(data, order, |b| f64::from(u32::from_le_bytes(b))),
        MI_SINGLE => conv(data, order, |b| f64::from(f32::from_le_bytes(b))),
        MI_DOUBLE => conv(data, order, f64::from_le_bytes),
        // 64-bit integers beyond 2^53 round to the nearest f64.
        MI_INT64 => conv(data, order, |b| i64::from_le_bytes(b) as f64),
        MI_UINT64 => conv(data, order, |b| u64::from_le_bytes(b) as f64),
        _ => return None,
    })
}

/// Applies `f` to each `N`-byte value of `data`, given to it in little-endian order.
fn conv<const N: usize>(data: &[u8], order: Order, f: impl Fn([u8; N]) -> f64) -> Vec<f64> {
    data.chunks_exact(N)
        .map(|c| {
            let mut b = take::<N>(c, 0).unwrap_or([0; N]);
            if order == Order::Big {
                b.reverse();
            }
            f(b)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::io::Write;

    const MX_DOUBLE: u32 = 6;
    const MX_UINT8: u32 = 9;
    const MI_UTF16: u32 = 17;

    /// Builds MAT file images, element by element, in one byte order.
    #[derive(Clone, Copy)]
    struct B(Order);

    impl B {
        fn u32(self, v: u32) -> [u8; 4] {
            match self.0 {
                Order::Little => v.to_le_bytes(),
                Order::Big => v.to_be_bytes(),
            }
        }

        /// `v` encoded as storage type `ty`, in this byte order.
        fn value(self, ty: u32, v: f64) -> Vec<u8> {
            let mut b = match ty {
                MI_INT8 => (v as i8).to_le_bytes().to_vec(),
                MI_UINT8 => (v as u8).to_le_bytes().to_vec(),
                MI_INT16 => (v as i16).to_le_bytes().to_vec(),
                MI_UINT16 | MI_UTF16 => (v as u16).to_le_bytes().to_vec(),
                MI_INT32 => (v as i32).to_le_bytes().to_vec(),
                MI_UINT32 => (v as u32).to_le_bytes().to_vec(),
                MI_SINGLE => (v as f32).to_le_bytes().to_vec(),
                MI_DOUBLE => v.to_le_bytes().to_vec(),
                MI_INT64 => (v as i64).to_le_bytes().to_vec(),
                MI_UINT64 => (v as u64).to_le_bytes().to_vec(),
                _ => panic!("no encoding for type {ty}"),
            };
            if self.0 == Order::Big {
                b.reverse();
            }
            b
        }

        fn header(self) -> Vec<u8> {
            let mut h = format!(
                "MATLAB 5.0 MAT-file, Platform: test, Created on: today, order {:?}",
                self.0
            )
            .into_bytes();
            h.resize(116, b' ');
            h.extend([0u8; 8]);
            h.extend(match self.0 {
                Order::Little => [0x00, 0x01, b'I', b'M'],
                Order::Big => [0x01, 0x00, b'M', b'I'],
            });
            h
        }

        /// A regular data element, padded to 8 bytes.
        fn elem(self, ty: u32, data: &[u8]) -> Vec<u8> {
            let mut e = [self.u32(ty), self.u32(data.len() as u32)].concat();
            e.extend(data);
            e.resize(e.len().next_multiple_of(8), 0);
            e
        }

        /// A small data element (at most 4 bytes of data, packed in the tag).
        fn small(self, ty: u32, data: &[u8]) -> Vec<u8> {
            assert!(data.len() <= 4);
            let mut e = self.u32(((data.len() as u32) << 16) | ty).to_vec();
            e.extend(data);
            e.resize(8, 0);
            e
        }

        /// Values as a real-part element of storage type `ty`.
        fn part(self, ty: u32, values: &[f64]) -> Vec<u8> {
            let data: Vec<u8> = values.iter().flat_map(|&v| self.value(ty, v)).collect();
            if data.len() <= 4 && !data.is_empty() {
                self.small(ty, &data)
            } else {
                self.elem(ty, &data)
            }
        }

        /// A miMATRIX element: flags, dims, name (small element when it fits), then `rest` (parts).
        fn matrix(self, flags: u32, dims: &[i32], name: &str, rest: &[Vec<u8>]) -> Vec<u8> {
            let flags = self.elem(MI_UINT32, &[self.u32(flags), self.u32(0)].concat());
            let dims: Vec<u8> = dims.iter().flat_map(|&d| self.u32(d as u32)).collect();
            let name = if name.len() <= 4 {
                self.small(MI_INT8, name.as_bytes())
            } else {
                self.elem(MI_INT8, name.as_bytes())
            };
            let body = [vec![flags, self.elem(MI_INT32, &dims), name], rest.to_vec()]
                .concat()
                .concat();
            self.elem(MI_MATRIX, &body)
        }

        /// A real double-class matrix stored as `ty`.
        fn numeric(self, name: &str, rows: i32, cols: i32, ty: u32, values: &[f64]) -> Vec<u8> {
            self.matrix(MX_DOUBLE, &[rows, cols], name, &[self.part(ty, values)])
        }

        /// A miCOMPRESSED element holding `inner` (unpadded, as MATLAB writes it).
        fn compressed(self, inner: &[u8]) -> Vec<u8> {
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(inner).unwrap();
            let data = z.finish().unwrap();
            [
                self.u32(MI_COMPRESSED).to_vec(),
                self.u32(data.len() as u32).to_vec(),
                data,
            ]
            .concat()
        }

        fn file(self, elems: &[Vec<u8>]) -> Vec<u8> {
            [vec![self.header()], elems.to_vec()].concat().concat()
        }
    }

    const LE: B = B(Order::Little);
    const BE: B = B(Order::Big);

    /// A file with a plain, a compressed and a skipped variable; also returns the top-level element boundaries.
    fn sample(b: B) -> (Vec<u8>, Vec<usize>) {
        let elems = vec![
            b.numeric("plain", 2, 3, MI_DOUBLE, &[1.0, 2.0, 3.0, 4.0, 5.5, -6.25]),
            b.compressed(&b.numeric("zipped", 3, 1, MI_INT16, &[-7.0, 0.0, 300.0])),
            b.matrix(4, &[1, 2], "txt", &[b.part(MI_UTF16, &[104.0, 105.0])]),
        ];
        let mut ends = vec![HEADER_LEN];
        for e in &elems {
            ends.push(ends[ends.len() - 1] + e.len());
        }
        (b.file(&elems), ends)
    }

    #[test]
    fn uncompressed_double_array() {
        let bytes = LE.file(&[LE.numeric("matrix_x", 2, 3, MI_DOUBLE, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.5])]);
        let f = read(&bytes).unwrap();
        assert!(f.skipped.is_empty());
        let a = f.array("matrix_x").unwrap();
        assert_eq!((a.rows, a.cols), (2, 3));
        assert_eq!(a.values, [1.0, 2.0, 3.0, 4.0, 5.0, 6.5]);
        assert_eq!(
            (a.get(0, 0), a.get(1, 0), a.get(0, 2), a.get(1, 2)),
            (1.0, 2.0, 5.0, 6.5)
        );
        assert!(f.array("nope").is_none());
        assert!(std::panic::catch_unwind(|| a.get(2, 0)).is_err());
        assert!(std::panic::catch_unwind(|| a.get(0, 3)).is_err());
    }

    #[test]
    fn small_element_name_and_small_data() {
        let el = LE.numeric("ab", 1, 1, MI_UINT8, &[200.0]);
        // The name's tag packs size 2 and type miINT8 into one word, data right after.
        assert_eq!(&el[8 + 16 + 16..8 + 16 + 16 + 8], &[1, 0, 2, 0, b'a', b'b', 0, 0]);
        let f = read(&LE.file(&[el])).unwrap();
        assert_eq!(
            f.arrays,
            [MatArray {
                name: "ab".into(),
                rows: 1,
                cols: 1,
                values: vec![200.0]
            }]
        );
    }

    #[test]
    fn big_endian_file() {
        let (bytes, _) = sample(BE);
        assert_eq!(&bytes[126..128], b"MI");
        let f = read(&bytes).unwrap();
        assert_eq!(f.array("plain").unwrap().values, [1.0, 2.0, 3.0, 4.0, 5.5, -6.25]);
        assert_eq!(f.array("zipped").unwrap().values, [-7.0, 0.0, 300.0]);
        assert_eq!(f.skipped, [("txt".to_string(), "char array".to_string())]);
        assert_eq!(read(&sample(LE).0).unwrap(), f);
    }

    #[test]
    fn int16_stored_double() {
        let vals = [-32768.0, -1.0, 0.0, 1.0, 32767.0, 12345.0];
        let f = read(&LE.file(&[LE.numeric("i16", 3, 2, MI_INT16, &vals)])).unwrap();
        let a = f.array("i16").unwrap();
        assert_eq!(a.values, vals);
        assert_eq!(a.get(2, 1).to_bits(), 12345.0f64.to_bits());
    }

    #[test]
    fn every_storage_type_converts() {
        let cases: [(u32, &[f64]); 10] = [
            (MI_INT8, &[-128.0, 127.0]),
            (MI_UINT8, &[0.0, 255.0]),
            (MI_INT16, &[-300.0, 300.0]),
            (MI_UINT16, &[0.0, 65535.0]),
            (MI_INT32, &[-2147483648.0, 7.0]),
            (MI_UINT32, &[4294967295.0, 1.0]),
            (MI_SINGLE, &[0.5, -1.25]),
            (MI_DOUBLE, &[0.1, -1e300]),
            (MI_INT64, &[-9007199254740992.0, 3.0]),
            (MI_UINT64, &[18446744073709551615.0, 9.0]),
        ];
        for b in [LE, BE] {
            for (ty, vals) in cases {
                let f = read(&b.file(&[b.numeric("v", 1, 2, ty, vals)])).unwrap();
                assert_eq!(f.arrays[0].values, vals, "storage type {ty}, {:?}", b.0);
            }
        }
    }

    #[test]
    fn logical_array() {
        let el = LE.matrix(
            0x0200 | MX_UINT8,
            &[2, 2],
            "mask",
            &[LE.part(MI_UINT8, &[1.0, 0.0, 1.0, 1.0])],
        );
        let f = read(&LE.file(&[el])).unwrap();
        assert_eq!(f.array("mask").unwrap().values, [1.0, 0.0, 1.0, 1.0]);
    }

    #[test]
    fn skips_char_struct_and_others() {
        let field = LE.numeric("", 1, 1, MI_DOUBLE, &[3.0]);
        let names = [b"a".as_slice(), &[0; 31]].concat();
        let st = LE.matrix(
            2,
            &[1, 1],
            "st",
            &[LE.small(MI_INT32, &LE.u32(32)), LE.elem(MI_INT8, &names), field],
        );
        let cell = LE.matrix(1, &[1, 1], "c", &[LE.numeric("", 1, 1, MI_DOUBLE, &[1.0])]);
        let imag = [LE.part(MI_DOUBLE, &[1.0]), LE.part(MI_DOUBLE, &[2.0])];
        let cplx = LE.matrix(0x0800 | MX_DOUBLE, &[1, 1], "z", &imag);
        let cube = LE.matrix(MX_DOUBLE, &[2, 1, 2], "cube", &[LE.part(MI_DOUBLE, &[1.0; 4])]);
        let sparse = LE.matrix(
            5,
            &[2, 2],
            "sp",
            &[LE.part(MI_INT32, &[0.0]), LE.part(MI_INT32, &[0.0, 1.0, 1.0])],
        );
        let chars = LE.matrix(
            4,
            &[1, 5],
            "greeting",
            &[LE.part(MI_UTF16, &[104.0, 101.0, 108.0, 108.0, 111.0])],
        );
        let after = LE.numeric("after", 1, 1, MI_DOUBLE, &[42.0]);
        let f = read(&LE.file(&[chars, st, cell, cplx, cube, sparse, after])).unwrap();
        let expect = [
            ("greeting", "char array"),
            ("st", "struct"),
            ("c", "cell array"),
            ("z", "complex"),
            ("cube", "3 dimensions (2 x 1 x 2)"),
            ("sp", "sparse matrix"),
        ];
        assert_eq!(f.skipped, expect.map(|(n, w)| (n.to_string(), w.to_string())));
        assert_eq!(f.arrays.len(), 1);
        assert_eq!(f.array("after").unwrap().values, [42.0]);
    }

    #[test]
    fn trailing_singleton_dims_and_empty_and_unnamed() {
        let col = LE.matrix(MX_DOUBLE, &[2, 1, 1], "col", &[LE.part(MI_DOUBLE, &[1.0, 2.0])]);
        let empty = LE.numeric("e", 0, 0, MI_DOUBLE, &[]);
        let unnamed = LE.numeric("", 1, 1, MI_UINT8, &[1.0]);
        let f = read(&LE.file(&[col, empty, unnamed, LE.elem(MI_MATRIX, &[])])).unwrap();
        assert_eq!(
            (f.arrays[0].rows, f.arrays[0].cols, f.arrays[0].values.len()),
            (2, 1, 2)
        );
        assert_eq!(
            (f.arrays[1].rows, f.arrays[1].cols, f.arrays[1].values.len()),
            (0, 0, 0)
        );
        assert_eq!(
            f.skipped.iter().map(|s| s.1.as_str()).collect::<Vec<_>>(),
            ["unnamed array (subsystem data)", "empty miMATRIX element"]
        );
        assert!(read(&LE.file(&[])).unwrap().arrays.is_empty());
    }

    #[test]
    fn overrun_message_names_offset_type_and_sizes() {
        let mut bytes = sample(LE).0;
        let len = bytes.len();
        bytes[128..136].copy_from_slice(&[LE.u32(15), LE.u32(99999)].concat());
        let msg = read(&bytes).unwrap_err().to_string();
        let want = format!(
            "byte 128: data element of type 15 claims 99999 bytes, only {} remain after its tag",
            len - 136
        );
        assert_eq!(msg, want);
    }

    #[test]
    fn errors_inside_compressed_data_name_both_offsets() {
        let bad = LE.numeric("bad", 3, 3, MI_DOUBLE, &[1.0; 4]);
        let bytes = LE.file(&[LE.numeric("ok", 1, 1, MI_DOUBLE, &[1.0]), LE.compressed(&bad)]);
        let msg = read(&bytes).unwrap_err().to_string();
        assert!(
            msg.starts_with("byte 48 of the data inflated from the miCOMPRESSED element at byte 192: "),
            "{msg}"
        );
        assert!(msg.contains("3 x 3 array needs 9 values"), "{msg}");
    }

    #[test]
    fn huge_dims_with_little_data_is_an_error() {
        let el = LE.numeric("big", i32::MAX, i32::MAX, MI_DOUBLE, &[1.0]);
        let msg = read(&LE.file(&[el])).unwrap_err().to_string();
        let want =
            "byte 176: 2147483647 x 2147483647 array needs 4611686014132420609 values, its real part (type 9) holds 1";
        assert_eq!(msg, want);
        let neg = LE.numeric("neg", -1, 2, MI_DOUBLE, &[1.0]);
        assert!(
            read(&LE.file(&[neg]))
                .unwrap_err()
                .to_string()
                .contains("negative dimension -1")
        );
    }

    #[test]
    fn inflate_is_capped_and_checked() {
        let big = LE.numeric("zeros", 1000, 100, MI_DOUBLE, &[0.0; 100_000]);
        let bytes = LE.file(&[LE.compressed(&big)]);
        assert!(bytes.len() < 4000, "{}", bytes.len());
        assert_eq!(read_limited(&bytes, big.len()).unwrap().arrays[0].values.len(), 100_000);
        let err = read_limited(&bytes, big.len() - 1).unwrap_err();
        assert!(
            matches!(
                err,
                MatError::TooLarge {
                    at: Pos {
                        offset: 128,
                        zlib_at: None
                    },
                    ..
                }
            ),
            "{err}"
        );
        // A second compressed element draws on the same per-file allowance.
        let twice = LE.file(&[LE.compressed(&big), LE.compressed(&big)]);
        assert!(matches!(
            read_limited(&twice, 2 * big.len() - 1),
            Err(MatError::TooLarge { .. })
        ));
        let mut corrupt = bytes.clone();
        corrupt[140..150].fill(0xff);
        assert!(
            matches!(read(&corrupt), Err(MatError::Zlib { .. })),
            "{:?}",
            read(&corrupt)
        );
    }

    #[test]
    fn truncated_zlib_stream_with_consistent_tag_is_an_error() {
        let el = LE.compressed(&LE.numeric("v", 1, 3, MI_DOUBLE, &[1.0, 2.0, 3.0]));
        for cut in 1..el.len() - 8 {
            let mut short = el[..el.len() - cut].to_vec();
            let size = LE.u32((short.len() - 8) as u32);
            short[4..8].copy_from_slice(&size);
            assert!(read(&LE.file(&[short])).is_err(), "cut {cut}");
        }
    }

    #[test]
    fn header_errors() {
        let msg = |b: &[u8]| read(b).unwrap_err().to_string();
        assert_eq!(
            msg(b"MATLAB 5.0"),
            "not a MAT v5 file (header needs 128 bytes, the input has only 10)"
        );
        let mut v73 = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 .".to_vec();
        v73.resize(512, b' ');
        v73.extend(HDF5_SIGNATURE);
        v73.resize(2048, 0);
        let m = msg(&v73);
        assert!(
            m.starts_with("not a MAT v5 file (header text \"MATLAB 7.3 MAT-file, Platform: GLNXA64"),
            "{m}"
        );
        assert!(
            m.contains("HDF5 signature at byte 512") && m.contains("'-v7'") && m.contains("CSV"),
            "{m}"
        );
        // A v4 file starts straight with a matrix header (type 0, rows, cols, imag flag, name length).
        let mut v4: Vec<u8> = [0u32, 2, 2, 0, 2].iter().flat_map(|v| v.to_le_bytes()).collect();
        v4.resize(200, 0);
        assert!(
            msg(&v4).contains("no \"IM\"/\"MI\" endian indicator at bytes 126-127, found 0x00 0x00"),
            "{}",
            msg(&v4)
        );
        let mut wrong = LE.header();
        wrong[124] = 2;
        assert!(msg(&wrong).contains("version 0x0102"), "{}", msg(&wrong));
    }

    #[test]
    fn bad_structure_is_reported() {
        let msg = |elems: &[Vec<u8>]| read(&LE.file(elems)).unwrap_err().to_string();
        assert!(msg(&[LE.elem(MI_DOUBLE, &[0; 8])]).contains("byte 128: top-level data element of type 9"));
        let no_real = LE.matrix(MX_DOUBLE, &[1, 1], "x", &[]);
        assert!(msg(&[no_real]).contains("miMATRIX element ends before its real part"));
        let text_real = LE.matrix(MX_DOUBLE, &[1, 1], "x", &[LE.elem(MI_UTF8, b"abcdefgh")]);
        assert!(msg(&[text_real]).contains("real part: expected data type"));
        let mut small = LE.file(&[LE.numeric("ab", 1, 1, MI_DOUBLE, &[1.0])]);
        small[128 + 40 + 2] = 9;
        assert!(
            read(&small)
                .unwrap_err()
                .to_string()
                .contains("small data element of type 1 claims 9 bytes")
        );
        let mut tail = LE.file(&[LE.numeric("x", 1, 1, MI_DOUBLE, &[1.0])]);
        tail.extend([0; 5]);
        assert_eq!(
            read(&tail).unwrap_err().to_string(),
            format!("byte {}: data element tag needs 8 bytes, only 5 remain", tail.len() - 5)
        );
    }

    #[test]
    fn every_truncation_errors_or_ends_on_an_element_boundary() {
        for b in [LE, BE] {
            let (bytes, ends) = sample(b);
            let full = read(&bytes).unwrap();
            for len in 0..bytes.len() {
                match read(&bytes[..len]) {
                    Err(_) => {}
                    Ok(f) => {
                        assert!(ends.contains(&len), "prefix of {len} bytes read without error");
                        assert!(f.arrays.len() + f.skipped.len() < full.arrays.len() + full.skipped.len());
                    }
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        #[test]
        fn mutated_images_never_panic(
            big_endian: bool,
            edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..12),
        ) {
            let (mut bytes, _) = sample(if big_endian { BE } else { LE });
            for (at, v) in edits {
                let i = at.index(bytes.len());
                bytes[i] = v;
            }
            let _ = read(&bytes);
        }

        #[test]
        fn random_tails_never_panic(big_endian: bool, tail in proptest::collection::vec(any::<u8>(), 0..300)) {
            let b = if big_endian { BE } else { LE };
            let _ = read(&[b.header(), tail].concat());
        }
    }
}
