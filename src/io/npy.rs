//! A small strict reader and writer of NumPy `.npy` files (format versions 1.0, 2.0, 3.0) for
//! the one kind of array the clips use: little-endian float64 (`'<f8'`), C order.
//!
//! File layout (NumPy enhancement proposal 1, "A simple file format for NumPy arrays"):
//!
//! ```text
//! \x93NUMPY  major minor  header_len (u16 LE for 1.x, u32 LE for 2.x/3.x)
//! {'descr': '<f8', 'fortran_order': False, 'shape': (600, 24), }   (padded with spaces, '\n')
//! raw data, product(shape) * 8 bytes
//! ```
//!
//! Anything else (another dtype, big-endian, Fortran order, a data block of the wrong length)
//! is an error that says what was found; no value is guessed or converted.
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

pub use super::files::NpyError;
use super::files::{open_capped, read_capped, write_atomic, InputError, OutputError, MAX_AXES};

const MAGIC: &[u8] = b"\x93NUMPY";

/// Largest `.npy` file read [bytes]: 1 GiB. The elegansbot kymograms are 58 KB and 115 KB; the
/// paper's clip as a recording (1160 frames × 128 nodes × 3 float64) is 3.6 MB.
pub const NPY_FILE_CAP_BYTES: u64 = 1 << 30;

/// A C-order float64 array read from an `.npy` file.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    /// Extent of each axis.
    pub shape: Vec<usize>,
    /// Values in C (row-major) order, `shape.iter().product()` of them.
    pub data: Vec<f64>,
}

/// Read a little-endian float64, C-order `.npy` file of at most [`NPY_FILE_CAP_BYTES`].
pub fn read_npy(path: &Path) -> Result<NpyArray, InputError> {
    let bytes = read_capped(path, NPY_FILE_CAP_BYTES, ".npy file")?;
    parse_npy(&bytes).map_err(|reason| InputError::Npy { path: path.to_path_buf(), reason: Box::new(reason) })
}

/// A little-endian float64, C-order `.npy` file of at most [`NPY_FILE_CAP_BYTES`] opened for
/// reading its values in order, a block at a time ([`NpyStream::read`]), so that a reader that
/// converts them as they come never holds the file and its array at once. Opening reads and
/// checks the header, and the length of the data against the shape, as [`read_npy`] does.
pub struct NpyStream {
    /// Extent of each axis.
    pub shape: Vec<usize>,
    path: PathBuf,
    reader: BufReader<File>,
    /// values not yet read
    left: usize,
}

/// Open `path` as an [`NpyStream`]: the same checks and errors as [`read_npy`].
pub fn open_npy(path: &Path) -> Result<NpyStream, InputError> {
    let open = |source| InputError::Open { path: path.to_path_buf(), source };
    let npy = |reason| InputError::Npy { path: path.to_path_buf(), reason: Box::new(reason) };
    let (file, len) = open_capped(path, NPY_FILE_CAP_BYTES, ".npy file")?;
    let mut reader = BufReader::new(file);
    // the magic string, the version and the header length, then the header (≤ the file's size)
    let mut head = vec![0u8; len.min(HEADER_LENGTH_END as u64) as usize];
    reader.read_exact(&mut head).map_err(open)?;
    let end = header_end(&head).map_err(npy)?;
    if end as u64 > len {
        return Err(npy(NpyError::TruncatedHeader { header_len: end - header_length_start(&head) }));
    }
    let known = head.len();
    head.resize(end, 0);
    reader.read_exact(&mut head[known..]).map_err(open)?;
    let (descr, shape, _) = npy_payload(&head).map_err(npy)?;
    let count = check_data(&descr, &shape, (len - end as u64) as usize).map_err(npy)?;
    Ok(NpyStream { shape, path: path.to_path_buf(), reader, left: count })
}

impl NpyStream {
    /// Fill `out` with the next `out.len()` values (C order); asking for more than are left is
    /// an error.
    pub fn read(&mut self, out: &mut [f64]) -> Result<(), InputError> {
        let open = |source| InputError::Open { path: self.path.clone(), source };
        if out.len() > self.left {
            let e = std::io::Error::new(std::io::ErrorKind::UnexpectedEof, "read past the array's values");
            return Err(open(e));
        }
        let mut bytes = [0u8; 8];
        for v in out.iter_mut() {
            self.reader.read_exact(&mut bytes).map_err(open)?;
            *v = f64::from_le_bytes(bytes);
        }
        self.left -= out.len();
        Ok(())
    }
}

/// Write `data` (C order) with the given shape as a version 1.0 `.npy` file, atomically.
pub fn write_npy(path: &Path, shape: &[usize], data: &[f64]) -> Result<(), OutputError> {
    let count: usize = shape.iter().product();
    if count != data.len() {
        return Err(OutputError::Invalid {
            path: path.to_path_buf(),
            reason: format!("shape {shape:?} holds {count} values, but {} were given", data.len()),
        });
    }
    write_atomic(path, &npy_bytes(shape, data))
}

/// Bytes of a version 1.0 `.npy` file (header padded so that the data start at a multiple of 64).
pub fn npy_bytes(shape: &[usize], data: &[f64]) -> Vec<u8> {
    let mut out = npy_header("<f8", shape);
    out.reserve(8 * data.len());
    for v in data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// The magic string and header of a version 1.0 `.npy` file of dtype `descr` (C order), padded
/// so that the data that follow start at a multiple of 64.
pub fn npy_header(descr: &str, shape: &[usize]) -> Vec<u8> {
    let dims = match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", shape.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")),
    };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {dims}, }}");
    let unpadded = MAGIC.len() + 2 + 2 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(MAGIC.len() + 4 + header.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out
}

/// Parse the bytes of an `.npy` file; the error is the reason, without the file name. Every
/// length read from the file (header length, shape) is checked against the bytes there are
/// before anything is allocated or indexed.
pub fn parse_npy(bytes: &[u8]) -> Result<NpyArray, NpyError> {
    let (descr, shape, body) = npy_payload(bytes)?;
    check_data(&descr, &shape, body.len())?;
    let data = body.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("chunks of 8"))).collect();
    Ok(NpyArray { shape, data })
}

/// The number of values of a float64 array of `shape` whose data are `found` bytes: an error
/// for another dtype than `<f8` or data of another length than the shape's.
fn check_data(descr: &str, shape: &[usize], found: usize) -> Result<usize, NpyError> {
    if descr != "<f8" {
        return Err(NpyError::Dtype { descr: preview(descr) });
    }
    let count = shape.iter().try_fold(1usize, |a, &n| a.checked_mul(n)).ok_or(NpyError::ShapeOverflow)?;
    let expected = count.checked_mul(8).ok_or(NpyError::ShapeOverflow)?;
    if found < expected {
        return Err(NpyError::TruncatedData { shape: shape.to_vec(), expected, found });
    }
    if found > expected {
        return Err(NpyError::TrailingBytes { extra: found - expected, shape: shape.to_vec(), expected });
    }
    Ok(count)
}

/// The byte after the header length of a version 2.0 or 3.0 file (version 1.0: two before).
const HEADER_LENGTH_END: usize = MAGIC.len() + 2 + 4;

/// Where the header of an `.npy` file starts, from its first [`HEADER_LENGTH_END`] bytes (or
/// fewer): after the magic string, the version and the header length, 2 bytes (1.0) or 4.
fn header_length_start(bytes: &[u8]) -> usize {
    MAGIC.len() + 2 + if bytes.get(MAGIC.len()) == Some(&1) { 2 } else { 4 }
}

/// Where the header of an `.npy` file ends (its data start), from the first
/// [`HEADER_LENGTH_END`] bytes of the file (or fewer): the magic string, the version and the
/// header length checked.
fn header_end(bytes: &[u8]) -> Result<usize, NpyError> {
    if bytes.len() < MAGIC.len() + 2 || &bytes[..MAGIC.len()] != MAGIC {
        return Err(NpyError::NoMagic);
    }
    let start = MAGIC.len() + 2;
    let header_len = match bytes[MAGIC.len()] {
        1 => {
            let b = bytes.get(start..start + 2).ok_or(NpyError::TruncatedHeaderLength)?;
            u16::from_le_bytes([b[0], b[1]]) as usize
        }
        2 | 3 => {
            let b = bytes.get(start..start + 4).ok_or(NpyError::TruncatedHeaderLength)?;
            u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize
        }
        major => return Err(NpyError::Version { major }),
    };
    Ok(header_length_start(bytes) + header_len)
}

/// The dtype, shape and data bytes of a C-order `.npy` file (the data not checked against the
/// shape).
pub fn npy_payload(bytes: &[u8]) -> Result<(String, Vec<usize>, &[u8]), NpyError> {
    let (start, end) = (header_length_start(bytes), header_end(bytes)?);
    let header = bytes.get(start..end).ok_or(NpyError::TruncatedHeader { header_len: end - start })?;
    let header = std::str::from_utf8(header).map_err(|_| NpyError::HeaderNotText)?;
    let (descr, fortran, shape) = parse_header(header)?;
    if fortran {
        return Err(NpyError::FortranOrder);
    }
    Ok((descr, shape, &bytes[end..]))
}

/// The three entries of the header dictionary: `descr`, `fortran_order`, `shape`.
fn parse_header(header: &str) -> Result<(String, bool, Vec<usize>), NpyError> {
    let inner = header
        .trim()
        .strip_prefix('{')
        .and_then(|h| h.strip_suffix('}'))
        .ok_or_else(|| NpyError::NotDictionary { header: preview(header) })?;
    let (mut descr, mut fortran, mut shape) = (None, None, None);
    let mut rest = inner.trim();
    let mut seen: Vec<&str> = Vec::new();
    while !rest.is_empty() {
        let (key, after) =
            quoted(rest).ok_or_else(|| NpyError::ExpectedKey { header: preview(inner), at: preview(rest) })?;
        if seen.contains(&key) {
            return Err(NpyError::DuplicateKey { key: preview(key) });
        }
        seen.push(key);
        let after = after
            .trim_start()
            .strip_prefix(':')
            .ok_or_else(|| NpyError::ExpectedColon { key: preview(key) })?
            .trim_start();
        let after = match key {
            "descr" => {
                let (v, a) = quoted(after).ok_or(NpyError::DescrNotString)?;
                descr = Some(v.to_string());
                a
            }
            "fortran_order" => {
                let (v, a) = if let Some(a) = after.strip_prefix("True") {
                    (true, a)
                } else if let Some(a) = after.strip_prefix("False") {
                    (false, a)
                } else {
                    return Err(NpyError::FortranNotBool { at: preview(after) });
                };
                fortran = Some(v);
                a
            }
            "shape" => {
                let body = after.strip_prefix('(').ok_or(NpyError::ShapeNotTuple)?;
                let close = body.find(')').ok_or(NpyError::ShapeNotClosed)?;
                let entries: Vec<&str> =
                    body[..close].split(',').map(str::trim).filter(|t| !t.is_empty()).take(MAX_AXES + 1).collect();
                if entries.len() > MAX_AXES {
                    return Err(NpyError::TooManyAxes);
                }
                let dims = entries
                    .into_iter()
                    .map(|t| t.parse::<usize>().map_err(|_| NpyError::ShapeEntry { entry: preview(t) }))
                    .collect::<Result<Vec<_>, _>>()?;
                shape = Some(dims);
                &body[close + 1..]
            }
            other => return Err(NpyError::UnknownKey { key: preview(other) }),
        };
        rest = after.trim_start();
        rest = rest.strip_prefix(',').unwrap_or(rest).trim_start();
    }
    Ok((
        descr.ok_or(NpyError::MissingKey { key: "descr" })?,
        fortran.ok_or(NpyError::MissingKey { key: "fortran_order" })?,
        shape.ok_or(NpyError::MissingKey { key: "shape" })?,
    ))
}

/// At most the first 40 characters of `s` (for messages about a malformed header).
fn preview(s: &str) -> String {
    match s.char_indices().nth(40) {
        Some((end, _)) => format!("{}…", &s[..end]),
        None => s.to_string(),
    }
}

/// A single- or double-quoted string at the start of `s`, and the rest after it.
fn quoted(s: &str) -> Option<(&str, &str)> {
    let q = s.chars().next().filter(|c| *c == '\'' || *c == '"')?;
    let end = s[1..].find(q)? + 1;
    Some((&s[1..end], &s[end + 1..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_round_trips_and_is_aligned() {
        let data: Vec<f64> = (0..24).map(|i| (i as f64).sin() * 1e-3).collect();
        for shape in [vec![24], vec![4, 6], vec![2, 4, 3]] {
            let b = npy_bytes(&shape, &data);
            let header_len = u16::from_le_bytes([b[8], b[9]]) as usize;
            assert_eq!((10 + header_len) % 64, 0);
            assert_eq!(parse_npy(&b).unwrap(), NpyArray { shape: shape.clone(), data: data.clone() });
        }
    }

    #[test]
    fn npy_version_2_header_and_double_quotes_are_read() {
        let header = "{\"descr\": \"<f8\", \"fortran_order\": False, \"shape\": (1, 2)}\n";
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&[2, 0]);
        b.extend_from_slice(&(header.len() as u32).to_le_bytes());
        b.extend_from_slice(header.as_bytes());
        b.extend_from_slice(&1.5f64.to_le_bytes());
        b.extend_from_slice(&(-2.0f64).to_le_bytes());
        assert_eq!(parse_npy(&b).unwrap(), NpyArray { shape: vec![1, 2], data: vec![1.5, -2.0] });
    }

    #[test]
    fn malformed_npy_says_what_is_wrong() {
        let good = npy_bytes(&[2, 3], &[0.0; 6]);
        let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
        let edit = |from: &str, to: &str| {
            let t = text(&good).replacen(from, to, 1);
            let mut b = good.clone();
            let start = good.windows(from.len()).position(|w| w == from.as_bytes()).unwrap();
            b.splice(start..start + from.len(), to.bytes());
            assert_eq!(b.len(), good.len(), "{t}");
            b
        };
        let e = parse_npy(&edit("<f8", ">f8")).unwrap_err().to_string();
        assert!(e.contains("dtype '>f8'") && e.contains("'<f8'"), "{e}");
        let e = parse_npy(&edit("<f8", "<f4")).unwrap_err().to_string();
        assert!(e.contains("dtype '<f4'"), "{e}");
        let e = parse_npy(&edit("False", "True ")).unwrap_err().to_string();
        assert!(e.contains("Fortran-order"), "{e}");
        let e = parse_npy(&good[..good.len() - 5]).unwrap_err().to_string();
        assert!(e.contains("truncated") && e.contains("48 data bytes") && e.contains("has 43"), "{e}");
        let e = parse_npy(&good[..20]).unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
        let e = parse_npy(b"PK\x03\x04 not npy").unwrap_err().to_string();
        assert!(e.contains("magic"), "{e}");
        let mut long = good.clone();
        long.extend_from_slice(&[0; 8]);
        assert!(parse_npy(&long).unwrap_err().to_string().contains("8 bytes after the data"));
        let e = parse_npy(&edit("(2, 3)", "(2,-3)")).unwrap_err().to_string();
        assert!(e.contains("'-3'"), "{e}");
        let e = parse_npy(&edit("'fortran_order'", "'descr'        ")).unwrap_err().to_string();
        assert_eq!(e, "header: key 'descr' given twice");
    }

    /// The stream reads what the whole-file reader reads, in blocks of any size, and refuses
    /// what it refuses with the same message: well-formed files of versions 1 and 2, and files
    /// cut at every length, with bytes after the data, of another dtype or a header length beyond
    /// the file.
    #[test]
    fn the_stream_reads_and_refuses_as_the_whole_file_reader() {
        let dir = tempfile::tempdir().unwrap();
        let data: Vec<f64> = (0..24).map(|i| (i as f64 * 0.7).cos() * 1e-4).collect();
        let good = npy_bytes(&[2, 4, 3], &data);
        let mut v2 = MAGIC.to_vec();
        let header = "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 12), }\n";
        v2.extend_from_slice(&[2, 0]);
        v2.extend_from_slice(&(header.len() as u32).to_le_bytes());
        v2.extend_from_slice(header.as_bytes());
        v2.extend(data.iter().flat_map(|v| v.to_le_bytes()));
        let mut files = vec![good.clone(), v2, [good.clone(), vec![0; 8]].concat()];
        files.extend((0..good.len()).step_by(7).map(|n| good[..n].to_vec()));
        files.push(String::from_utf8_lossy(&good).replacen("<f8", "<f4", 1).into_bytes());
        files.push([MAGIC, &[1, 0, 0xff, 0xff]].concat());
        for (k, bytes) in files.iter().enumerate() {
            let path = dir.path().join(format!("f{k}.npy"));
            std::fs::write(&path, bytes).unwrap();
            let whole = read_npy(&path).map_err(|e| e.to_string());
            let streamed = open_npy(&path).map_err(|e| e.to_string()).and_then(|mut a| {
                let mut values = vec![0.0; a.shape.iter().product()];
                for block in values.chunks_mut(5) {
                    a.read(block).map_err(|e| e.to_string())?;
                }
                assert!(a.read(&mut [0.0]).is_err(), "nothing after the last value");
                Ok(NpyArray { shape: a.shape.clone(), data: values })
            });
            assert_eq!(streamed, whole, "file {k} ({} bytes)", bytes.len());
        }
        assert!(read_npy(&dir.path().join("f0.npy")).is_ok() && read_npy(&dir.path().join("f3.npy")).is_err());
    }

    /// Lengths from the file (header length, shape) that overflow or exceed the bytes present.
    #[test]
    fn hostile_lengths_are_errors() {
        let header = |h: &str, version: u8| {
            let mut b = MAGIC.to_vec();
            b.extend_from_slice(&[version, 0]);
            if version == 1 {
                b.extend_from_slice(&(h.len() as u16).to_le_bytes());
            } else {
                b.extend_from_slice(&(h.len() as u32).to_le_bytes());
            }
            b.extend_from_slice(h.as_bytes());
            b
        };
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&[2, 0, 0xff, 0xff, 0xff, 0xff]);
        assert_eq!(
            parse_npy(&b).unwrap_err().to_string(),
            "truncated: the header is 4294967295 bytes, the file ends before it does"
        );
        let e = parse_npy(&header("{'descr': '<f8', 'fortran_order': False, 'shape': (4294967296, 4294967296, 2)}", 1));
        assert_eq!(e.unwrap_err().to_string(), "shape overflows");
        let e = parse_npy(&header("{'descr': '<f8', 'fortran_order': False, 'shape': (1000000000000,)}", 3));
        assert_eq!(
            e.unwrap_err().to_string(),
            "truncated: shape [1000000000000] needs 8000000000000 data bytes, the file has 0"
        );
        let axes = vec!["1"; 65].join(",");
        let e = parse_npy(&header(&format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({axes})}}"), 1));
        assert_eq!(e.unwrap_err().to_string(), "header: shape has more than 64 axes, the most an array has");
        let long = "x".repeat(100_000);
        let e = parse_npy(&header(&format!("{{'descr': '{long}', 'fortran_order': False, 'shape': (1,)}}"), 2));
        assert_eq!(
            e.unwrap_err().to_string(),
            format!("dtype '{}…', expected little-endian float64 '<f8'", "x".repeat(40))
        );
    }
}
