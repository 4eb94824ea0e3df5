//! Writing `fields.npz` from the raw rows of a clip (`super::compact`) in bounded memory,
//! whatever the clip's length. Each column of the archive is its values over all frames, XORed
//! with the previous frame and split into byte planes, plane 0 of every frame before plane 1:
//! no column can be written before its last frame is read. So the raw rows are read once, in
//! blocks of frames ([`BLOCK_BYTES`]); each block's part of every plane of every column is
//! deflated on its own (a segment ending on a sync flush, [`super::compact::deflate_segment`],
//! so that segments concatenate to one deflate stream) and appended to a spill file, with an
//! index; then the archive is written member by member, each column's segments copied from the
//! spill in plane order. Memory: a block and its segments; disk: the spill, about the size of
//! the archive, while it is written. An archive beyond 4 GiB gets the Zip64 records
//! (APPNOTE 4.3.14–4.3.15, 4.5.3) that NumPy's `np.load` (Python's `zipfile`) reads.
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::compact::{deflate_segment, COMPACT_FILE, CURVATURE_COLUMNS, RAW_CURVATURE, RAW_FIELDS};
use super::files::{OutputError, ZipError};
use super::npy::npy_header;

/// Raw values read at a time [bytes] (a block of whole frames; at least one frame). Writing
/// the archive holds about twice this: the block and its deflated segments.
pub const BLOCK_BYTES: usize = 4 << 20;
/// Offsets and sizes from which the Zip64 records are written: the 32-bit fields' limit.
const ZIP64_FROM: u64 = u32::MAX as u64;

/// One member of the archive: its name, CRC-32, uncompressed size and where its compressed
/// bytes are (`Inline` for the small ones, else `Spilled` segments of the spill file, in order).
struct Member {
    name: String,
    crc: u32,
    size: u64,
    data: Data,
}

enum Data {
    Inline(Vec<u8>),
    /// (offset, length) in the spill file of each segment, in the member's order
    Spilled(Vec<(u64, u64)>),
}

impl Member {
    fn compressed_size(&self) -> u64 {
        match &self.data {
            Data::Inline(b) => b.len() as u64,
            Data::Spilled(s) => s.iter().map(|(_, n)| n).sum::<u64>() + 2,
        }
    }
}

/// The spill file: compressed segments appended, each remembered by (offset, length).
struct Spill {
    path: PathBuf,
    file: BufWriter<File>,
    at: u64,
}

impl Spill {
    fn append(&mut self, bytes: &[u8]) -> Result<(u64, u64), OutputError> {
        let path = &self.path;
        self.file.write_all(bytes).map_err(|source| OutputError::Io { path: path.clone(), source })?;
        let at = self.at;
        self.at += bytes.len() as u64;
        Ok((at, bytes.len() as u64))
    }
}

/// The columns of one raw file (`names`, `per` values per frame each) as members whose
/// segments go to `spill`: the raw file read once, a block of frames at a time.
fn spill_columns(
    raw: &Path,
    names: &[&str],
    (frames, per): (usize, usize),
    spill: &mut Spill,
    block_bytes: usize,
) -> Result<Vec<Member>, OutputError> {
    let io = |source| OutputError::Io { path: raw.to_path_buf(), source };
    let nc = names.len();
    let row = per * nc;
    let block = (block_bytes / (8 * row).max(1)).max(1);
    let headers: Vec<Vec<u8>> = names.iter().map(|_| npy_header("|u1", &[8, frames, per])).collect();
    let mut crc: Vec<Vec<crc32fast::Hasher>> = vec![vec![crc32fast::Hasher::new(); 8]; nc];
    let mut segments: Vec<Vec<Vec<(u64, u64)>>> = vec![vec![Vec::new(); 8]; nc];
    let mut reader = BufReader::with_capacity(1 << 20, File::open(raw).map_err(io)?);
    let (mut previous, mut bytes) = (vec![0u8; 8 * row], vec![0u8; 8 * row * block]);
    let word = |b: &[u8], i: usize| u64::from_le_bytes(b[8 * i..8 * i + 8].try_into().unwrap_or([0; 8]));
    let mut done = 0;
    while done < frames {
        let n = block.min(frames - done);
        let bytes = &mut bytes[..8 * row * n];
        reader.read_exact(bytes).map_err(io)?;
        let bytes = &*bytes;
        // per (column, plane): the block's bytes of that plane, deflated as one segment; only
        // the segments are kept (a plane lives in its task)
        let parts: Vec<(crc32fast::Hasher, Vec<u8>)> = (0..nc * 8)
            .into_par_iter()
            .map(|cp| {
                let (c, k) = (cp / 8, cp % 8);
                let plane: Vec<u8> = (0..n * per)
                    .map(|i| {
                        let (f, j) = (i / per, i % per);
                        let at = j * nc + c;
                        let w = word(bytes, f * row + at);
                        let before = if f == 0 { word(&previous, at) } else { word(bytes, (f - 1) * row + at) };
                        ((w ^ before) >> (8 * k)) as u8
                    })
                    .collect();
                let mut h = crc32fast::Hasher::new();
                h.update(&plane);
                Ok((h, deflate_segment(&plane)?))
            })
            .collect::<Result<_, ZipError>>()
            .map_err(|reason| OutputError::Zip { path: raw.to_path_buf(), reason })?;
        for (cp, (h, packed)) in parts.into_iter().enumerate() {
            crc[cp / 8][cp % 8].combine(&h);
            segments[cp / 8][cp % 8].push(spill.append(&packed)?);
        }
        previous.copy_from_slice(&bytes[8 * row * (n - 1)..]);
        done += n;
    }
    let mut members = Vec::with_capacity(nc);
    for (c, name) in names.iter().enumerate() {
        let mut h = crc32fast::Hasher::new();
        h.update(&headers[c]);
        let head = spill.append(
            &deflate_segment(&headers[c]).map_err(|reason| OutputError::Zip { path: raw.to_path_buf(), reason })?,
        )?;
        for k in 0..8 {
            h.combine(&crc[c][k]);
        }
        let mut data = vec![head];
        data.extend(segments[c].iter().flatten());
        let size = headers[c].len() as u64 + 8 * (frames * per) as u64;
        members.push(Member { name: format!("{name}.npy"), crc: h.finalize(), size, data: Data::Spilled(data) });
    }
    Ok(members)
}

/// The frame numbers as the member `frame.npy` (stored, small).
fn frame_member(frames: &[i64]) -> Result<Member, ZipError> {
    let mut npy = npy_header("<i8", &[frames.len()]);
    npy.extend(frames.iter().flat_map(|f| f.to_le_bytes()));
    let mut packed = deflate_segment(&npy)?;
    packed.extend([0x03, 0x00]); // an empty final block
    Ok(Member {
        name: "frame.npy".into(),
        crc: crc32fast::hash(&npy),
        size: npy.len() as u64,
        data: Data::Inline(packed),
    })
}

/// The number of frames × values per frame of a raw file of `len` bytes holding `frames`
/// frames of `columns` columns, if it does.
fn per_frame(len: u64, frames: usize, columns: usize) -> Option<usize> {
    let values = len / 8;
    let rows = values.checked_div(columns as u64)?;
    (len.is_multiple_of(8) && values.is_multiple_of(columns as u64) && frames > 0 && rows.is_multiple_of(frames as u64))
        .then_some((rows / frames as u64) as usize)
}

/// Write `dir/fields.npz` from the raw rows in `dir` (`RAW_FIELDS`, `RAW_CURVATURE`) of the
/// frames `frames`, `field_columns` values per node and `CURVATURE_COLUMNS` per element, in
/// bounded memory (the module doc); written under a temporary name and renamed into place.
pub fn write_compact(dir: &Path, frames: &[i64], field_columns: &[&str]) -> Result<PathBuf, OutputError> {
    write_compact_with(dir, frames, field_columns, (ZIP64_FROM, BLOCK_BYTES))
}

/// [`write_compact`] with the Zip64 records from offsets of `zip64_from` bytes on and blocks of
/// `block_bytes` (tests).
fn write_compact_with(
    dir: &Path,
    frames: &[i64],
    field_columns: &[&str],
    (zip64_from, block_bytes): (u64, usize),
) -> Result<PathBuf, OutputError> {
    let path = dir.join(COMPACT_FILE);
    let spill_path = dir.join(format!(".{COMPACT_FILE}.spill"));
    let tmp = dir.join(format!(".{COMPACT_FILE}.{}.tmp", std::process::id()));
    let result = (|| {
        let zip_error = |reason: ZipError| OutputError::Zip { path: path.clone(), reason };
        let nf = frames.len();
        let file = File::create(&spill_path).map_err(|source| OutputError::Io { path: spill_path.clone(), source })?;
        let mut spill = Spill { path: spill_path.clone(), file: BufWriter::new(file), at: 0 };
        let mut members = vec![frame_member(frames).map_err(zip_error)?];
        for (raw, columns) in [(RAW_FIELDS, field_columns), (RAW_CURVATURE, &CURVATURE_COLUMNS[..])] {
            let p = dir.join(raw);
            let len = std::fs::metadata(&p).map_err(|source| OutputError::Io { path: p.clone(), source })?.len();
            let per = per_frame(len, nf, columns.len()).ok_or_else(|| OutputError::Invalid {
                path: path.clone(),
                reason: format!("{raw} holds {} values, not {nf} frames of {} columns", len / 8, columns.len()),
            })?;
            members.extend(spill_columns(&p, columns, (nf, per), &mut spill, block_bytes)?);
        }
        spill.file.flush().map_err(|source| OutputError::Io { path: spill_path.clone(), source })?;
        drop(spill);
        write_zip(&tmp, &members, &spill_path, zip64_from)?;
        std::fs::rename(&tmp, &path).map_err(|source| OutputError::Io { path: path.clone(), source })
    })();
    let _ = std::fs::remove_file(&spill_path);
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map(|()| path)
}

/// Write the archive of `members` to `path`, spilled segments copied from `spill`.
fn write_zip(path: &Path, members: &[Member], spill: &Path, zip64_from: u64) -> Result<(), OutputError> {
    let io = |p: &Path| {
        let p = p.to_path_buf();
        move |source| OutputError::Io { path: p.clone(), source }
    };
    let zip_error = |reason: ZipError| OutputError::Zip { path: path.to_path_buf(), reason };
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path).map_err(io(path))?);
    let mut src = File::open(spill).map_err(io(spill))?;
    let (mut at, mut central) = (0u64, Vec::new());
    let mut buf = vec![0u8; 1 << 20];
    for m in members {
        let (csize, size) = (m.compressed_size(), m.size);
        if csize >= ZIP64_FROM || size >= ZIP64_FROM {
            return Err(zip_error(ZipError::TooLarge { what: m.name.clone() }));
        }
        let mut local = Vec::with_capacity(30 + m.name.len());
        local.extend(0x0403_4b50u32.to_le_bytes());
        common(&mut local, m, csize);
        local.extend(0u16.to_le_bytes());
        local.extend(m.name.as_bytes());
        out.write_all(&local).map_err(io(path))?;
        match &m.data {
            Data::Inline(b) => out.write_all(b).map_err(io(path))?,
            Data::Spilled(segments) => {
                for &(offset, len) in segments {
                    src.seek(SeekFrom::Start(offset)).map_err(io(spill))?;
                    let mut left = len as usize;
                    while left > 0 {
                        let k = left.min(buf.len());
                        src.read_exact(&mut buf[..k]).map_err(io(spill))?;
                        out.write_all(&buf[..k]).map_err(io(path))?;
                        left -= k;
                    }
                }
                out.write_all(&[0x03, 0x00]).map_err(io(path))?; // an empty final block
            }
        }
        central_entry(&mut central, m, csize, at, zip64_from);
        at += local.len() as u64 + csize;
    }
    let count =
        u16::try_from(members.len()).map_err(|_| zip_error(ZipError::TooManyMembers { count: members.len() }))?;
    out.write_all(&central).map_err(io(path))?;
    out.write_all(&end_records(at, central.len() as u64, count, zip64_from)).map_err(io(path))?;
    let file = out.into_inner().map_err(|e| OutputError::Io { path: path.to_path_buf(), source: e.into_error() })?;
    file.sync_all().map_err(io(path))
}

/// The fields a local header and a central directory entry share: version 2.0, no flags,
/// deflate, 1980-01-01 00:00, CRC, sizes, name length.
fn common(out: &mut Vec<u8>, m: &Member, csize: u64) {
    for v in [20u16, 0, 8, 0, 0x21] {
        out.extend(v.to_le_bytes());
    }
    out.extend(m.crc.to_le_bytes());
    out.extend((csize as u32).to_le_bytes());
    out.extend((m.size as u32).to_le_bytes());
    out.extend((m.name.len() as u16).to_le_bytes());
}

/// The central directory entry of `m`, whose local header is at `offset`: beyond
/// `zip64_from`, the offset goes into a Zip64 extra field (0x0001) and the 32-bit one is
/// 0xFFFFFFFF.
fn central_entry(central: &mut Vec<u8>, m: &Member, csize: u64, offset: u64, zip64_from: u64) {
    let zip64 = offset >= zip64_from;
    central.extend(0x0201_4b50u32.to_le_bytes());
    central.extend(if zip64 { 45u16 } else { 20u16 }.to_le_bytes());
    common(central, m, csize);
    central.extend(if zip64 { 12u16 } else { 0u16 }.to_le_bytes()); // extra field length
    central.extend([0u8; 10]); // comment length, disk, internal and external attributes
    central.extend(if zip64 { u32::MAX } else { offset as u32 }.to_le_bytes());
    central.extend(m.name.as_bytes());
    if zip64 {
        central.extend(1u16.to_le_bytes());
        central.extend(8u16.to_le_bytes());
        central.extend(offset.to_le_bytes());
    }
}

/// The end of the archive: the central directory of `cd_size` bytes at `cd_offset`, `count`
/// members; with the Zip64 end record and its locator first when the directory lies beyond
/// `zip64_from`.
fn end_records(cd_offset: u64, cd_size: u64, count: u16, zip64_from: u64) -> Vec<u8> {
    let mut out = Vec::new();
    let zip64 = cd_offset >= zip64_from || cd_offset + cd_size >= zip64_from;
    if zip64 {
        let record = cd_offset + cd_size;
        out.extend(0x0606_4b50u32.to_le_bytes());
        out.extend(44u64.to_le_bytes());
        out.extend([45u16, 45].iter().flat_map(|v| v.to_le_bytes()));
        out.extend([0u32, 0].iter().flat_map(|v| v.to_le_bytes()));
        out.extend([u64::from(count), u64::from(count), cd_size, cd_offset].iter().flat_map(|v| v.to_le_bytes()));
        out.extend(0x0706_4b50u32.to_le_bytes());
        out.extend(0u32.to_le_bytes());
        out.extend(record.to_le_bytes());
        out.extend(1u32.to_le_bytes());
    }
    out.extend(0x0605_4b50u32.to_le_bytes());
    out.extend([0u8; 4]);
    out.extend(count.to_le_bytes());
    out.extend(count.to_le_bytes());
    out.extend((cd_size.min(u64::from(u32::MAX)) as u32).to_le_bytes());
    out.extend(if zip64 { u32::MAX } else { cd_offset as u32 }.to_le_bytes());
    out.extend(0u16.to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::compact::read_compact;

    /// Raw rows of `frames` frames written as `dir/name`: value `f(frame, row, column)`.
    fn raw(dir: &Path, name: &str, (frames, per, nc): (usize, usize, usize), f: impl Fn(usize, usize, usize) -> f64) {
        let mut b = Vec::new();
        for i in 0..frames {
            for j in 0..per {
                for c in 0..nc {
                    b.extend(f(i, j, c).to_le_bytes());
                }
            }
        }
        std::fs::write(dir.join(name), b).unwrap();
    }

    /// A clip of more frames than a block holds (several blocks, the XOR carried across them),
    /// written with and without the Zip64 records, reads back bit for bit; the spill is gone.
    #[test]
    fn blocks_and_zip64_read_back_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let block_bytes = 1 << 16;
        let (frames, per) = (3 * block_bytes / (8 * 40 * 3) + 7, 40);
        let value = |i: usize, j: usize, c: usize| ((i as f64) * 0.01 + j as f64).sin() * 10f64.powi(c as i32 - 3);
        raw(dir.path(), RAW_FIELDS, (frames, per, 3), value);
        raw(dir.path(), RAW_CURVATURE, (frames, per - 1, CURVATURE_COLUMNS.len()), |i, j, c| value(i, j, c % 3) * 2.0);
        let numbers: Vec<i64> = (0..frames as i64).map(|f| f + 10).collect();
        for zip64_from in [ZIP64_FROM, 1000] {
            let p = write_compact_with(dir.path(), &numbers, &["a", "b", "c"], (zip64_from, block_bytes)).unwrap();
            let c = read_compact(&p).unwrap();
            assert_eq!(c.frame, numbers);
            for (k, name) in ["a", "b", "c"].iter().enumerate() {
                let (n, v) = &c.columns[*name];
                assert_eq!(*n, per);
                assert!(
                    v.iter().enumerate().all(|(i, x)| x.to_bits() == value(i / per, i % per, k).to_bits()),
                    "{name}"
                );
            }
            // an independent reader: Python's zipfile, which NumPy's np.load uses (skipped
            // where there is no python3)
            let check = "import sys, zipfile; z = zipfile.ZipFile(sys.argv[1]); assert z.testzip() is None; print(len(z.namelist()))";
            if let Ok(o) = std::process::Command::new("python3").args(["-c", check]).arg(&p).output() {
                assert!(o.status.success(), "zipfile: {}", String::from_utf8_lossy(&o.stderr));
                assert_eq!(String::from_utf8_lossy(&o.stdout).trim(), (4 + CURVATURE_COLUMNS.len()).to_string());
            }
            let (n, v) = &c.columns["kappa2_per_m"];
            assert_eq!((*n, v.len()), (per - 1, frames * (per - 1)));
            let names: Vec<String> = std::fs::read_dir(dir.path())
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            assert!(names.iter().all(|n| !n.starts_with('.')), "{names:?}");
        }
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
        std::fs::write(dir.path().join(RAW_CURVATURE), 0.5f64.to_le_bytes().repeat(CURVATURE_COLUMNS.len() * 2))
            .unwrap();
        assert!(crate::io::compact::entropy(&crate::io::compact::encode_column(&noise, 2)[..noise.len()]) > 7.9);
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
        let nc = CURVATURE_COLUMNS.len();
        let curv: Vec<f64> = (0..2 * 2 * nc).map(|i| -(i as f64)).collect();
        raw(RAW_FIELDS, &fields);
        raw(RAW_CURVATURE, &curv);
        let p = write_compact(dir.path(), &[4, 5], &["a", "b"]).unwrap();
        let c = read_compact(&p).unwrap();
        assert_eq!(c.frame, vec![4, 5]);
        assert_eq!(c.columns["a"], (3, fields.iter().step_by(2).copied().collect::<Vec<_>>()));
        assert_eq!(c.columns["kappa3_per_m"], (2, curv.iter().skip(3).step_by(nc).copied().collect::<Vec<_>>()));
        std::fs::write(&p, b"PK not really").unwrap();
        assert!(read_compact(&p).is_err());
        raw(RAW_FIELDS, &fields[..5]);
        assert!(write_compact(dir.path(), &[4, 5], &["a", "b"]).is_err());
    }
}
