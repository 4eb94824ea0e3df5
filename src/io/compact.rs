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
use std::path::Path;

use super::files::{read_capped, InputError};
pub use super::files::{CompactError, ZipError};
use super::npy::npy_payload;

/// The compact file in a clip's output folder.
pub const COMPACT_FILE: &str = "fields.npz";
/// The raw rows of a compact clip while it runs: per node, the values of `fields.csv` after
/// `frame,node`; per element, those of `curvature.csv` after `frame`.
pub const RAW_FIELDS: &str = "fields.f64";
pub const RAW_CURVATURE: &str = "curvature.f64";
/// Columns of `curvature.csv` after `frame`, one row per element: its midpoint, the curvature
/// κ = A ∂sα [1/m] (eq. 28), and its stress resultants (`model::resultants::resultants`): the
/// internal force n [N] and moment m [N m] in global components (eqs. 13, 15), then in the
/// directors' (`n1` along d1 … `m3` the twisting moment about d3).
pub const CURVATURE_COLUMNS: [&str; 16] = [
    "s_mid_m",
    "kappa1_per_m",
    "kappa2_per_m",
    "kappa3_per_m",
    "n_x_n",
    "n_y_n",
    "n_z_n",
    "m_x_nm",
    "m_y_nm",
    "m_z_nm",
    "n1_n",
    "n2_n",
    "n3_n",
    "m1_nm",
    "m2_nm",
    "m3_nm",
];
/// Largest `fields.npz` read [bytes]: 4 GiB (what a zip without its 64-bit extension holds).
pub const COMPACT_FILE_CAP_BYTES: u64 = 1 << 32;

/// How the per-node output of a clip is written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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

/// Shannon entropy of the bytes of `b` [bits per byte].
pub(crate) fn entropy(b: &[u8]) -> f64 {
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
pub(super) fn deflate_segment(data: &[u8]) -> Result<Vec<u8>, ZipError> {
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

/// A `fields.npz` read back: the frame numbers and every column over frames × nodes (fields)
/// or frames × elements (curvature), row-major.
#[derive(Clone, Debug, Default)]
pub struct CompactClip {
    pub frame: Vec<i64>,
    /// name → (values per frame, values)
    pub columns: BTreeMap<String, (usize, Vec<f64>)>,
}

/// Read a `fields.npz` written by [`super::compact_write::write_compact`].
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

fn u64_at(b: &[u8], at: usize) -> Result<usize, CompactError> {
    let v =
        b.get(at..at + 8).map(|s| u64::from_le_bytes(s.try_into().unwrap_or([0; 8]))).ok_or(CompactError::Truncated)?;
    usize::try_from(v).map_err(|_| CompactError::Truncated)
}

/// The local header offset of a central directory entry's Zip64 extra field (id 0x0001,
/// holding only the offset: the sizes of our members fit 32 bits), among its `len` bytes of
/// extra fields at `at`.
fn zip64_offset(b: &[u8], mut at: usize, len: usize) -> Result<usize, CompactError> {
    let end = at + len;
    while at + 4 <= end {
        let (id, size) = (u16_at(b, at)?, u16_at(b, at + 2)?);
        if id == 1 && size >= 8 {
            return u64_at(b, at + 4);
        }
        at += 4 + size;
    }
    Err(CompactError::CorruptDirectory)
}

/// The members of a zip archive (stored or deflated), by name.
fn unzip(b: &[u8]) -> Result<BTreeMap<String, Vec<u8>>, CompactError> {
    let eocd = (0..b.len().saturating_sub(21))
        .rev()
        .take(1 << 16)
        .find(|&i| b[i..].starts_with(&0x0605_4b50u32.to_le_bytes()))
        .ok_or(CompactError::NotZip)?;
    let (count, mut at) = (u16_at(b, eocd + 10)?, u32_at(b, eocd + 16)?);
    if at == u32::MAX as usize {
        // Zip64: the locator before the end record gives the Zip64 end record, and that the
        // directory's offset
        let record = u64_at(b, eocd.checked_sub(12).ok_or(CompactError::Truncated)?)?;
        at = u64_at(b, record + 48)?;
    }
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
        let local = if local == u32::MAX as usize { zip64_offset(b, at + 46 + nlen, xlen)? } else { local };
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
}
