//! The compact output of a clip (`cosserat run --output-format compact`): the per-node fields of
//! `fields.csv` and the element curvature of `curvature.csv` (and so the VTK files, which hold
//! nothing else) in one NumPy `fields.npz` at full f64 precision, instead of the CSVs and one
//! `.vtp` per frame. Each array is a column over frames × nodes (or elements), stored as its
//! IEEE bits XORed with the previous frame's (a smooth time series leaves the sign, exponent and
//! high mantissa bytes zero) and byte-shuffled (byte k of every value together, the HDF5
//! "shuffle" filter), then deflated in the zip. `docs/output.md` says how to read it.
//!
//! While the clip runs, the rows go raw (f64, little-endian) to `fields.f64` and
//! `curvature.f64`, which the resume journal cuts back like CSVs; `fields.npz` is written
//! (atomically) when the clip ends, and the raw files go with the journal.
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::files::{read_capped, write_atomic, InputError, OutputError};
pub use super::files::{CompactError, ZipError};
use super::npy::{npy_header, npy_payload};

/// The compact file in a clip's output folder.
pub const COMPACT_FILE: &str = "fields.npz";
/// The raw rows of a compact clip while it runs: per node, the values of `fields.csv` after
/// `frame,node`; per element, those of `curvature.csv` after `frame`.
pub const RAW_FIELDS: &str = "fields.f64";
pub const RAW_CURVATURE: &str = "curvature.f64";
/// Columns of `curvature.csv` after `frame`.
pub const CURVATURE_COLUMNS: [&str; 4] = ["s_mid_m", "kappa1_per_m", "kappa2_per_m", "kappa3_per_m"];
/// Largest `fields.npz` read [bytes]: 4 GiB (what a zip without its 64-bit extension holds).
pub const COMPACT_FILE_CAP_BYTES: u64 = 1 << 32;

/// How the per-node output of a clip is written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputFormat {
    /// `fields.csv`, `curvature.csv` and ParaView `vtk/frame_NNNNN.vtp` + `clip.pvd`
    #[default]
    Csv,
    /// one `fields.npz` (NumPy) with every per-node field at full precision, 4-6x smaller
    Compact,
}

/// The encoded bytes of one column: `values` (`frames` rows, frame-major) as u64 bits, each
/// XORed with the same position of the previous frame, then byte plane k (k = 0 least
/// significant) of all of them after plane k - 1.
pub fn encode_column(values: &[f64], frames: usize) -> Vec<u8> {
    let n = values.len();
    let per = n.checked_div(frames).unwrap_or(0);
    let mut out = vec![0u8; 8 * n];
    for (i, v) in values.iter().enumerate() {
        let prev = if i >= per && per > 0 { values[i - per].to_bits() } else { 0 };
        let w = v.to_bits() ^ prev;
        for k in 0..8 {
            out[k * n + i] = (w >> (8 * k)) as u8;
        }
    }
    out
}

/// The inverse of [`encode_column`]: `bytes` (8 byte planes) back to values of rows `per` long.
pub fn decode_column(bytes: &[u8], per: usize) -> Vec<f64> {
    let n = bytes.len() / 8;
    let mut words: Vec<u64> =
        (0..n).map(|i| (0..8).fold(0u64, |w, k| w | (u64::from(bytes[k * n + i]) << (8 * k)))).collect();
    if per > 0 {
        for i in per..n {
            words[i] ^= words[i - per];
        }
    }
    words.into_iter().map(f64::from_bits).collect()
}

/// One `.npy` member of the archive: its name and the bytes of the `.npy` file, in parts
/// (header, byte planes) that are deflated one by one.
struct Member {
    name: String,
    parts: Vec<Vec<u8>>,
}

/// The encoded column `name` of `frames` × `per` values as a `|u1` array of shape
/// `(8, frames, per)`, one part per byte plane.
fn column_member(name: &str, values: &[f64], frames: usize, per: usize) -> Member {
    let mut parts = vec![npy_header("|u1", &[8, frames, per])];
    let planes = encode_column(values, frames);
    parts.extend(planes.chunks(values.len().max(1)).map(<[u8]>::to_vec));
    Member { name: format!("{name}.npy"), parts }
}

/// Shannon entropy of the bytes of `b` [bits per byte].
fn entropy(b: &[u8]) -> f64 {
    let mut count = [0usize; 256];
    for &x in b {
        count[x as usize] += 1;
    }
    let n = b.len().max(1) as f64;
    count.iter().filter(|&&c| c > 0).map(|&c| -(c as f64 / n) * (c as f64 / n).log2()).sum()
}

/// `data` as deflate blocks ending on a byte boundary and not final (a sync flush), so that
/// such segments, each compressed on its own, concatenate to one deflate stream. Noise (the low
/// mantissa bytes, more than 7.9 bits per byte) is stored; the rest is deflated at level 3.
fn deflate_segment(data: &[u8]) -> Result<Vec<u8>, ZipError> {
    if entropy(data) > 7.9 {
        // stored blocks: a header byte (not final, type 00), LEN and its complement, the bytes
        let mut out = Vec::with_capacity(data.len() + 5 * (data.len() / 65535 + 1));
        for block in data.chunks(65535) {
            out.push(0);
            out.extend((block.len() as u16).to_le_bytes());
            out.extend((!(block.len() as u16)).to_le_bytes());
            out.extend(block);
        }
        return Ok(out);
    }
    let mut c = flate2::Compress::new(flate2::Compression::new(3), false);
    let mut out = Vec::with_capacity(data.len() + data.len() / 64 + 64);
    loop {
        if out.capacity() - out.len() < 64 {
            out.reserve(out.capacity().max(4096));
        }
        let done = c.total_in() as usize;
        c.compress_vec(&data[done..], &mut out, flate2::FlushCompress::Sync).map_err(ZipError::Deflate)?;
        if c.total_in() as usize == data.len() && out.len() < out.capacity() {
            return Ok(out);
        }
    }
}

/// Bytes of a zip archive of `members`, each deflated (in parallel), without the 64-bit
/// extension; `Err` when a member or the archive exceeds its 4 GiB.
fn zip_bytes(members: &[Member]) -> Result<Vec<u8>, ZipError> {
    let packed: Vec<(u32, usize, Vec<u8>)> = members
        .par_iter()
        .map(|m| {
            let mut crc = crc32fast::Hasher::new();
            let mut data = Vec::new();
            for part in &m.parts {
                crc.update(part);
                data.extend(deflate_segment(part)?);
            }
            data.extend([0x03, 0x00]); // an empty final block
            Ok((crc.finalize(), m.parts.iter().map(Vec::len).sum(), data))
        })
        .collect::<Result<_, ZipError>>()?;
    let u32_of = |n: usize, what: &str| u32::try_from(n).map_err(|_| ZipError::TooLarge { what: what.to_string() });
    let (mut out, mut central) = (Vec::new(), Vec::new());
    for (m, (crc, plain, data)) in members.iter().zip(&packed) {
        let offset = u32_of(out.len(), "the archive")?;
        let (csize, usize_) = (u32_of(data.len(), &m.name)?, u32_of(*plain, &m.name)?);
        // version 2.0, no flags, deflate, 1980-01-01 00:00
        let common = |out: &mut Vec<u8>| {
            for v in [20u16, 0, 8, 0, 0x21] {
                out.extend(v.to_le_bytes());
            }
            for v in [*crc, csize, usize_] {
                out.extend(v.to_le_bytes());
            }
            out.extend((m.name.len() as u16).to_le_bytes());
            out.extend(0u16.to_le_bytes());
        };
        out.extend(0x0403_4b50u32.to_le_bytes());
        common(&mut out);
        out.extend(m.name.as_bytes());
        out.extend(data);
        central.extend(0x0201_4b50u32.to_le_bytes());
        central.extend(20u16.to_le_bytes());
        common(&mut central);
        central.extend([0u8; 10]); // comment length, disk, internal and external attributes
        central.extend(offset.to_le_bytes());
        central.extend(m.name.as_bytes());
    }
    let (cd_offset, cd_size) = (u32_of(out.len(), "the archive")?, u32_of(central.len(), "the directory")?);
    out.extend(central);
    out.extend(0x0605_4b50u32.to_le_bytes());
    out.extend([0u8; 4]);
    let count = u16::try_from(members.len()).map_err(|_| ZipError::TooManyMembers { count: members.len() })?;
    out.extend(count.to_le_bytes());
    out.extend(count.to_le_bytes());
    out.extend(cd_size.to_le_bytes());
    out.extend(cd_offset.to_le_bytes());
    out.extend(0u16.to_le_bytes());
    Ok(out)
}

/// Write `dir/fields.npz` from the raw rows in `dir` (`RAW_FIELDS`, `RAW_CURVATURE`) of the
/// frames `frames`, `field_columns` values per node and `CURVATURE_COLUMNS` per element.
pub fn write_compact(dir: &Path, frames: &[i64], field_columns: &[&str]) -> Result<PathBuf, OutputError> {
    let path = dir.join(COMPACT_FILE);
    let invalid = |reason: String| OutputError::Invalid { path: path.clone(), reason };
    let zip_error = |reason: ZipError| OutputError::Zip { path: path.clone(), reason };
    let read = |name: &str| -> Result<Vec<f64>, OutputError> {
        let p = dir.join(name);
        let bytes = std::fs::read(&p).map_err(|source| OutputError::Io { path: p, source })?;
        Ok(bytes.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).collect())
    };
    let nf = frames.len();
    let mut members = Vec::new();
    let mut npy = npy_header("<i8", &[nf]);
    npy.extend(frames.iter().flat_map(|f| f.to_le_bytes()));
    members.push(Member { name: "frame.npy".into(), parts: vec![npy] });
    for (raw, columns) in [(RAW_FIELDS, field_columns), (RAW_CURVATURE, &CURVATURE_COLUMNS[..])] {
        let values = read(raw)?;
        let (nc, rows) = (columns.len(), values.len() / columns.len().max(1));
        if nf == 0 || rows % nf != 0 || values.len() % nc != 0 {
            return Err(invalid(format!("{raw} holds {} values, not {nf} frames of {nc} columns", values.len())));
        }
        let per = rows / nf;
        let mut cols: Vec<Vec<f64>> = vec![Vec::with_capacity(rows); nc];
        for (i, v) in values.into_iter().enumerate() {
            cols[i % nc].push(v);
        }
        let cols: Vec<Member> =
            cols.par_iter().zip(columns.par_iter()).map(|(col, name)| column_member(name, col, nf, per)).collect();
        members.extend(cols);
    }
    write_atomic(&path, &zip_bytes(&members).map_err(zip_error)?)?;
    Ok(path)
}

/// A `fields.npz` read back: the frame numbers and every column over frames × nodes (fields)
/// or frames × elements (curvature), row-major.
#[derive(Clone, Debug, Default)]
pub struct CompactClip {
    pub frame: Vec<i64>,
    /// name → (values per frame, values)
    pub columns: BTreeMap<String, (usize, Vec<f64>)>,
}

/// Read a `fields.npz` written by [`write_compact`].
pub fn read_compact(path: &Path) -> Result<CompactClip, InputError> {
    let bytes = read_capped(path, COMPACT_FILE_CAP_BYTES, "compact clip file")?;
    parse_compact(&bytes).map_err(|reason| InputError::Compact { path: path.to_path_buf(), reason: Box::new(reason) })
}

fn u16_at(b: &[u8], at: usize) -> Result<usize, CompactError> {
    b.get(at..at + 2).map(|s| u16::from_le_bytes([s[0], s[1]]) as usize).ok_or(CompactError::Truncated)
}

fn u32_at(b: &[u8], at: usize) -> Result<usize, CompactError> {
    b.get(at..at + 4).map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as usize).ok_or(CompactError::Truncated)
}

/// The members of a zip archive (stored or deflated), by name.
fn unzip(b: &[u8]) -> Result<BTreeMap<String, Vec<u8>>, CompactError> {
    let eocd = (0..b.len().saturating_sub(21))
        .rev()
        .take(1 << 16)
        .find(|&i| b[i..].starts_with(&0x0605_4b50u32.to_le_bytes()))
        .ok_or(CompactError::NotZip)?;
    let (count, mut at) = (u16_at(b, eocd + 10)?, u32_at(b, eocd + 16)?);
    let mut out = BTreeMap::new();
    for _ in 0..count {
        if u32_at(b, at)? != 0x0201_4b50 {
            return Err(CompactError::CorruptDirectory);
        }
        let (method, crc, csize, usize_) =
            (u16_at(b, at + 10)?, u32_at(b, at + 16)?, u32_at(b, at + 20)?, u32_at(b, at + 24)?);
        let (nlen, xlen, clen, local) =
            (u16_at(b, at + 28)?, u16_at(b, at + 30)?, u16_at(b, at + 32)?, u32_at(b, at + 42)?);
        let name = b.get(at + 46..at + 46 + nlen).ok_or(CompactError::Truncated)?;
        let name = String::from_utf8_lossy(name).into_owned();
        at += 46 + nlen + xlen + clen;
        let start = local + 30 + u16_at(b, local + 26)? + u16_at(b, local + 28)?;
        let data = b.get(start..start + csize).ok_or_else(|| CompactError::MemberTruncated { name: name.clone() })?;
        let plain = match method {
            0 => data.to_vec(),
            8 => {
                // at most one byte more than the directory says: a corrupt size is refused, not
                // inflated without bound
                let mut plain = Vec::new();
                let mut d = std::io::Read::take(flate2::read::DeflateDecoder::new(data), usize_ as u64 + 1);
                std::io::Read::read_to_end(&mut d, &mut plain)
                    .map_err(|error| CompactError::Inflate { name: name.clone(), error })?;
                plain
            }
            method => return Err(CompactError::Method { name, method }),
        };
        if plain.len() != usize_ || crc32fast::hash(&plain) as usize != crc {
            return Err(CompactError::Corrupt { name });
        }
        out.insert(name, plain);
    }
    Ok(out)
}

fn parse_compact(bytes: &[u8]) -> Result<CompactClip, CompactError> {
    let mut clip = CompactClip::default();
    for (name, npy) in unzip(bytes)? {
        let (descr, shape, data) =
            npy_payload(&npy).map_err(|reason| CompactError::Npy { name: name.clone(), reason })?;
        let stem = name.strip_suffix(".npy").unwrap_or(&name).to_string();
        match (stem.as_str(), descr.as_str(), shape.as_slice()) {
            ("frame", "<i8", [n]) if n.checked_mul(8) == Some(data.len()) => {
                clip.frame = data.chunks_exact(8).map(|c| i64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).collect()
            }
            (_, "|u1", [8, f, per]) if f.checked_mul(*per).and_then(|n| n.checked_mul(8)) == Some(data.len()) => {
                clip.columns.insert(stem, (*per, decode_column(data, *per)));
            }
            _ => return Err(CompactError::UnexpectedArray { name, descr, shape }),
        }
    }
    Ok(clip)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_round_trip_bit_for_bit() {
        let v: Vec<f64> =
            (0..60).map(|i| (i as f64 * 0.37).sin() * 1e-3 + if i == 7 { f64::NAN } else { 0.0 }).collect();
        let back = decode_column(&encode_column(&v, 5), 12);
        assert!(v.iter().zip(&back).all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn noise_is_stored_and_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let mut state = 7u64;
        let noise: Vec<f64> = (0..3 * 70_000)
            .map(|_| {
                // splitmix64
                state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
                let z = (state ^ (state >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
                let z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
                f64::from_bits((z ^ (z >> 31)) >> 2)
            })
            .collect();
        let bytes: Vec<u8> = noise.iter().flat_map(|x| x.to_le_bytes()).collect();
        std::fs::write(dir.path().join(RAW_FIELDS), bytes).unwrap();
        std::fs::write(dir.path().join(RAW_CURVATURE), 0.5f64.to_le_bytes().repeat(4 * 2)).unwrap();
        assert!(entropy(&encode_column(&noise, 2)[..noise.len()]) > 7.9);
        let p = write_compact(dir.path(), &[0, 1], &["a", "b", "c"]).unwrap();
        let c = read_compact(&p).unwrap();
        for (k, name) in ["a", "b", "c"].iter().enumerate() {
            let expected: Vec<u64> = noise.iter().skip(k).step_by(3).map(|v| v.to_bits()).collect();
            assert_eq!(c.columns[*name].1.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), expected, "{name}");
        }
    }

    #[test]
    fn archive_round_trips_and_refuses_garbage() {
        let dir = tempfile::tempdir().unwrap();
        let raw = |name: &str, v: &[f64]| {
            std::fs::write(dir.path().join(name), v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<_>>()).unwrap()
        };
        let fields: Vec<f64> = (0..2 * 3 * 2).map(|i| i as f64 * 0.1).collect();
        let curv: Vec<f64> = (0..2 * 2 * 4).map(|i| -(i as f64)).collect();
        raw(RAW_FIELDS, &fields);
        raw(RAW_CURVATURE, &curv);
        let p = write_compact(dir.path(), &[4, 5], &["a", "b"]).unwrap();
        let c = read_compact(&p).unwrap();
        assert_eq!(c.frame, vec![4, 5]);
        assert_eq!(c.columns["a"], (3, fields.iter().step_by(2).copied().collect::<Vec<_>>()));
        assert_eq!(c.columns["kappa3_per_m"], (2, curv.iter().skip(3).step_by(4).copied().collect::<Vec<_>>()));
        std::fs::write(&p, b"PK not really").unwrap();
        assert!(read_compact(&p).is_err());
        raw(RAW_FIELDS, &fields[..5]);
        assert!(write_compact(dir.path(), &[4, 5], &["a", "b"]).is_err());
    }
}
