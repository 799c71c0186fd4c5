//! NumPy's `.npz` as a streamed output (`docs/model-format.md`, "Binary
//! output"): a ZIP archive, stored (not compressed), of two `.npy` arrays,
//!
//! - `columns.npy`: the column names, a 1-D array of `<U<L>` (UTF-32);
//! - `data.npy`: the rows, a 2-D array of `<f8` (little-endian doubles), C
//!   order, one row per sample, one column per name,
//!
//! so that `numpy.load("run.npz")` reads it without mstar. Rows are appended
//! as the run makes them; the `.npy` shape, the entry's CRC-32 and sizes and
//! the central directory are written at the end (`Npz::finish`), which is
//! why the file must be seekable. ZIP64 fields are always used for
//! `data.npy`, so a run may write more than 4 GiB.
//!
//! Formats: the `.npy` format, versions 1.0 and 2.0 (NumPy Enhancement
//! Proposal 1, <https://numpy.org/neps/nep-0001-npy-format.html>); ZIP,
//! PKWARE's APPNOTE.TXT 6.3.9, §4.3 (local headers, central directory,
//! ZIP64 end records) and §4.5.3 (the ZIP64 extra field).

use std::io::{self, Read, Seek, SeekFrom, Write};

/// `0xFFFF_FFFF`: "see the ZIP64 extra field".
const ZIP64_MARK: u32 = u32::MAX;
/// Digits kept for the row count in `data.npy`'s header (room for any `u64`).
const ROW_DIGITS: usize = 20;
/// DOS date of the entries: 1980-01-01, 00:00 (the format's epoch; the
/// output of a plan is then the same bytes on every run).
const DOS_DATE: u16 = (1 << 5) | 1;

/// One stored entry of the archive.
#[derive(Clone, Debug)]
struct Entry {
    name: &'static str,
    /// Offset of its local header.
    offset: u64,
    /// Its data's size and CRC-32.
    size: u64,
    crc: u32,
}

/// The layout of an `.npz` being written: what [`Npz::head`] put before the
/// rows, and what [`Npz::finish`] patches and appends.
#[derive(Debug)]
pub(crate) struct Npz {
    columns: usize,
    entries: [Entry; 2],
    /// Offset of `data.npy`'s `.npy` header, and its length.
    npy_at: u64,
    npy_len: usize,
    /// CRC-32 of the row bytes written so far.
    rows_crc: crc32fast::Hasher,
}

impl Npz {
    /// The layout for `names`, and the bytes before the first row.
    pub(crate) fn head(names: &[String]) -> (Self, Vec<u8>) {
        let columns_npy = names_array(names);
        let mut out = Vec::new();
        let columns = Entry {
            name: "columns.npy",
            offset: 0,
            size: columns_npy.len() as u64,
            crc: crc32fast::hash(&columns_npy),
        };
        local_header(&mut out, &columns, false);
        out.extend_from_slice(&columns_npy);
        let data = Entry {
            name: "data.npy",
            offset: out.len() as u64,
            size: 0,
            crc: 0,
        };
        local_header(&mut out, &data, true);
        let npy_at = out.len() as u64;
        let npy = npy_header("<f8", &format!("({:ROW_DIGITS$}, {})", 0, names.len()));
        out.extend_from_slice(&npy);
        let npz = Self {
            columns: names.len(),
            entries: [columns, data],
            npy_at,
            npy_len: npy.len(),
            rows_crc: crc32fast::Hasher::new(),
        };
        (npz, out)
    }

    /// Bytes of the head ([`head`](Self::head)): where the rows begin.
    pub(crate) fn rows_at(&self) -> u64 {
        self.npy_at + self.npy_len as u64
    }

    /// Bytes per row.
    pub(crate) fn row_bytes(&self) -> usize {
        8 * self.columns
    }

    /// Appends a row of `values` (as many as the columns) to `out`.
    pub(crate) fn encode(values: impl Iterator<Item = f64>, out: &mut Vec<u8>) {
        for x in values {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }

    /// Notes that `rows` (whole rows' bytes) reached the file.
    pub(crate) fn written(&mut self, rows: &[u8]) {
        self.rows_crc.update(rows);
    }

    /// Ends the archive in `file` after `rows` rows: the row count in the
    /// `.npy` header, the entry's CRC-32 and sizes, the central directory.
    /// `reread`: the row CRC is not known (rows were cut after a failed
    /// write), read the rows back for it.
    pub(crate) fn finish(
        &mut self,
        file: &mut std::fs::File,
        rows: u64,
        reread: bool,
    ) -> io::Result<()> {
        let end = self.rows_at() + rows * self.row_bytes() as u64;
        file.set_len(end)?;
        if reread {
            self.rows_crc = crc_of(file, self.rows_at(), end)?;
        }
        let shape = format!("({rows:ROW_DIGITS$}, {})", self.columns);
        let npy = npy_header("<f8", &shape);
        debug_assert_eq!(npy.len(), self.npy_len);
        let mut crc = crc32fast::Hasher::new();
        crc.update(&npy);
        crc.combine(&self.rows_crc);
        let data = &mut self.entries[1];
        data.size = end - self.npy_at;
        data.crc = crc.finalize();
        // The local header again, now with its CRC and sizes.
        let mut local = Vec::new();
        local_header(&mut local, data, true);
        file.seek(SeekFrom::Start(data.offset))?;
        file.write_all(&local)?;
        file.write_all(&npy)?;
        file.seek(SeekFrom::Start(end))?;
        file.write_all(&self.tail(end))
    }

    /// Bytes [`finish`](Self::finish) appends at `end`.
    pub(crate) fn tail_len(&self) -> usize {
        self.tail(0).len()
    }

    /// The central directory at `at` and the end records.
    fn tail(&self, at: u64) -> Vec<u8> {
        let mut out = Vec::new();
        for (k, e) in self.entries.iter().enumerate() {
            central_header(&mut out, e, k == 1);
        }
        let cd_size = out.len() as u64;
        let zip64_end = at + cd_size;
        // ZIP64 end of central directory record (APPNOTE §4.3.14).
        put32(&mut out, 0x0606_4b50);
        put64(&mut out, 44);
        put16(&mut out, 45);
        put16(&mut out, 45);
        put32(&mut out, 0);
        put32(&mut out, 0);
        put64(&mut out, 2);
        put64(&mut out, 2);
        put64(&mut out, cd_size);
        put64(&mut out, at);
        // Its locator (§4.3.15).
        put32(&mut out, 0x0706_4b50);
        put32(&mut out, 0);
        put64(&mut out, zip64_end);
        put32(&mut out, 1);
        // End of central directory record (§4.3.16).
        put32(&mut out, 0x0605_4b50);
        put16(&mut out, 0);
        put16(&mut out, 0);
        put16(&mut out, 2);
        put16(&mut out, 2);
        put32(&mut out, u32::try_from(cd_size).unwrap_or(ZIP64_MARK));
        put32(&mut out, u32::try_from(at).unwrap_or(ZIP64_MARK));
        put16(&mut out, 0);
        out
    }
}

/// The `columns` and `data` arrays of an `.npz` as `mstar run` writes it (or
/// `numpy.savez(f, columns=names, data=rows)`, stored, not compressed): the
/// names and the rows (row-major), as read back by `mstar animate`.
///
/// # Errors
/// A file that is not such an archive, with what is missing or malformed.
pub fn read(path: &std::path::Path) -> io::Result<(Vec<String>, Vec<f64>)> {
    let zip = std::fs::read(path)?;
    let bad = |what: &str| io::Error::new(io::ErrorKind::InvalidData, what.to_string());
    let entries =
        entries(&zip).ok_or_else(|| bad("not a ZIP archive (no end of central directory)"))?;
    let find = |name: &str| {
        entries
            .iter()
            .find(|(n, ..)| n == name)
            .and_then(|&(_, at, size, method)| (method == 0).then_some((at, size)))
            .and_then(|(at, size)| zip.get(at..at.checked_add(size)?))
            .ok_or_else(|| {
                bad(&format!(
                    "no stored {name} (write it with mstar run --out FILE.npz)"
                ))
            })
    };
    let (descr, shape, bytes) =
        npy(find("columns.npy")?).ok_or_else(|| bad("columns.npy is not an .npy array"))?;
    let width: usize = descr
        .strip_prefix("<U")
        .and_then(|w| w.parse().ok())
        .filter(|&w: &usize| w > 0)
        .ok_or_else(|| bad("columns.npy is not an array of text (<U…)"))?;
    if shape.len() != 1 || bytes.len() != 4 * width * shape[0] {
        return Err(bad("columns.npy has the wrong shape"));
    }
    let names = bytes
        .chunks(4 * width)
        .map(|name| {
            name.chunks(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .take_while(|&c| c != 0)
                .map(|c| char::from_u32(c).unwrap_or(char::REPLACEMENT_CHARACTER))
                .collect()
        })
        .collect::<Vec<String>>();
    let (descr, shape, bytes) =
        npy(find("data.npy")?).ok_or_else(|| bad("data.npy is not an .npy array"))?;
    if descr != "<f8"
        || shape.len() != 2
        || shape[1] != names.len()
        || bytes.len() != 8 * shape[0] * shape[1]
    {
        return Err(bad(
            "data.npy is not a (rows, columns) array of <f8 matching columns.npy",
        ));
    }
    let data = bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
        .collect();
    Ok((names, data))
}

/// Little-endian integers of `b` at `at` (`None` past the end).
fn le(b: &[u8], at: usize, n: usize) -> Option<u64> {
    let bytes = b.get(at..at.checked_add(n)?)?;
    Some(
        bytes
            .iter()
            .rev()
            .fold(0, |x, &byte| (x << 8) | u64::from(byte)),
    )
}

/// The entries of a ZIP archive: name, data offset, size, method (APPNOTE
/// §4.3.12-§4.3.16, ZIP64 where a field says `0xFFFFFFFF`).
fn entries(zip: &[u8]) -> Option<Vec<(String, usize, usize, u64)>> {
    let eocd = (0..=zip.len().checked_sub(22)?)
        .rev()
        .find(|&i| le(zip, i, 4) == Some(0x0605_4b50))?;
    let (mut count, mut cd) = (le(zip, eocd + 10, 2)?, le(zip, eocd + 16, 4)?);
    if cd == u64::from(ZIP64_MARK) || count == 0xFFFF {
        let locator = eocd.checked_sub(20)?;
        let end64 = usize::try_from(le(zip, locator + 8, 8)?).ok()?;
        count = le(zip, end64 + 32, 8)?;
        cd = le(zip, end64 + 48, 8)?;
    }
    let mut at = usize::try_from(cd).ok()?;
    let mut out = Vec::new();
    for _ in 0..count {
        if le(zip, at, 4)? != 0x0201_4b50 {
            return None;
        }
        let method = le(zip, at + 10, 2)?;
        let (name_len, extra_len, comment) = (
            le(zip, at + 28, 2)?,
            le(zip, at + 30, 2)?,
            le(zip, at + 32, 2)?,
        );
        let (name_len, extra_len) = (
            usize::try_from(name_len).ok()?,
            usize::try_from(extra_len).ok()?,
        );
        let name = String::from_utf8_lossy(zip.get(at + 46..at + 46 + name_len)?).into_owned();
        let mut size = le(zip, at + 24, 4)?;
        let mut offset = le(zip, at + 42, 4)?;
        let extra = zip.get(at + 46 + name_len..at + 46 + name_len + extra_len)?;
        if le(extra, 0, 2) == Some(1) {
            // ZIP64: the sizes, then the offset, each only where marked.
            let mut k = 4;
            if size == u64::from(ZIP64_MARK) {
                size = le(extra, k, 8)?;
                k += 16;
            }
            if offset == u64::from(ZIP64_MARK) {
                offset = le(extra, k, 8)?;
            }
        }
        let local = usize::try_from(offset).ok()?;
        let skip = usize::try_from(le(zip, local + 26, 2)? + le(zip, local + 28, 2)?).ok()?;
        out.push((name, local + 30 + skip, usize::try_from(size).ok()?, method));
        at += 46 + name_len + extra_len + usize::try_from(comment).ok()?;
    }
    Some(out)
}

/// An `.npy` array's `descr`, shape and data (version 1, 2 or 3, C order).
fn npy(bytes: &[u8]) -> Option<(String, Vec<usize>, &[u8])> {
    if bytes.get(..6)? != b"\x93NUMPY" {
        return None;
    }
    let (len, start) = match bytes.get(6)? {
        1 => (le(bytes, 8, 2)?, 10),
        _ => (le(bytes, 8, 4)?, 12),
    };
    let end = start + usize::try_from(len).ok()?;
    let header = std::str::from_utf8(bytes.get(start..end)?).ok()?;
    let value = |key: &str| {
        let from = header.find(key)? + key.len();
        Some(header[from..].trim_start_matches([':', ' ', '\'']))
    };
    let descr = value("'descr'")?.split('\'').next()?.to_string();
    if !value("'fortran_order'")?.starts_with("False") {
        return None;
    }
    let shape = value("'shape'")?;
    let shape = shape.get(1..shape.find(')')?)?;
    let shape = shape
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().ok())
        .collect::<Option<Vec<usize>>>()?;
    Some((descr, shape, bytes.get(end..)?))
}

/// The CRC-32 of the bytes `from..to` of `file`.
fn crc_of(file: &mut std::fs::File, from: u64, to: u64) -> io::Result<crc32fast::Hasher> {
    let mut crc = crc32fast::Hasher::new();
    file.seek(SeekFrom::Start(from))?;
    let mut left = to - from;
    let mut chunk = vec![0_u8; 1 << 16];
    while left > 0 {
        let n = usize::try_from(left.min(chunk.len() as u64)).unwrap_or(chunk.len());
        file.read_exact(&mut chunk[..n])?;
        crc.update(&chunk[..n]);
        left -= n as u64;
    }
    Ok(crc)
}

/// A `.npy` header for `descr` and `shape` (a Python tuple), padded with
/// spaces so that the data starts at a multiple of 64 bytes (NEP 1); version
/// 2.0 when the header is longer than version 1.0's 65 535 bytes.
fn npy_header(descr: &str, shape: &str) -> Vec<u8> {
    let dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    let v1 = dict.len() + 1 + 10 <= usize::from(u16::MAX);
    let prefix = if v1 { 10 } else { 12 };
    let total = (prefix + dict.len() + 1).div_ceil(64) * 64;
    let len = total - prefix;
    let mut out = b"\x93NUMPY".to_vec();
    if v1 {
        out.extend_from_slice(&[1, 0]);
        put16(&mut out, u16::try_from(len).unwrap_or(u16::MAX));
    } else {
        out.extend_from_slice(&[2, 0]);
        put32(&mut out, u32::try_from(len).unwrap_or(u32::MAX));
    }
    out.extend_from_slice(dict.as_bytes());
    out.resize(total - 1, b' ');
    out.push(b'\n');
    out
}

/// `columns.npy`: the names as a `<U<L>` array, `L` the longest name's
/// characters (at least 1), each name's characters as UTF-32 LE padded with
/// zeros.
fn names_array(names: &[String]) -> Vec<u8> {
    let width = names
        .iter()
        .map(|n| n.chars().count())
        .max()
        .unwrap_or(0)
        .max(1);
    let mut out = npy_header(&format!("<U{width}"), &format!("({},)", names.len()));
    out.reserve(4 * width * names.len());
    for name in names {
        let mut count = 0;
        for c in name.chars() {
            put32(&mut out, u32::from(c));
            count += 1;
        }
        out.resize(out.len() + 4 * (width - count), 0);
    }
    out
}

/// A local file header (APPNOTE §4.3.7), with a ZIP64 extra field when
/// `zip64`.
fn local_header(out: &mut Vec<u8>, e: &Entry, zip64: bool) {
    put32(out, 0x0403_4b50);
    common_fields(out, e, zip64);
    name_and_extra(out, e, zip64);
}

/// A central directory header (APPNOTE §4.3.12).
fn central_header(out: &mut Vec<u8>, e: &Entry, zip64: bool) {
    put32(out, 0x0201_4b50);
    put16(out, 45); // made by
    common_fields(out, e, zip64);
    put16(out, 0); // comment
    put16(out, 0); // disk
    put16(out, 0); // internal attributes
    put32(out, 0); // external attributes
    put32(out, u32::try_from(e.offset).unwrap_or(ZIP64_MARK));
    name_and_extra(out, e, zip64);
}

/// The fields both headers share, from "version needed" to the extra
/// field's length: stored, no flags, [`DOS_DATE`], the CRC-32 and sizes (in
/// the ZIP64 field when `zip64`).
fn common_fields(out: &mut Vec<u8>, e: &Entry, zip64: bool) {
    put16(out, if zip64 { 45 } else { 20 });
    put16(out, 0); // flags
    put16(out, 0); // stored
    put16(out, 0); // time
    put16(out, DOS_DATE);
    put32(out, e.crc);
    let small = u32::try_from(e.size).unwrap_or(ZIP64_MARK);
    let size = if zip64 { ZIP64_MARK } else { small };
    put32(out, size);
    put32(out, size);
    put16(out, e.name.len() as u16);
    put16(out, if zip64 { 20 } else { 0 });
}

/// The entry's name, then its ZIP64 extra field (both sizes) when `zip64`.
fn name_and_extra(out: &mut Vec<u8>, e: &Entry, zip64: bool) {
    out.extend_from_slice(e.name.as_bytes());
    if zip64 {
        put16(out, 0x0001);
        put16(out, 16);
        put64(out, e.size);
        put64(out, e.size);
    }
}

fn put16(out: &mut Vec<u8>, x: u16) {
    out.extend_from_slice(&x.to_le_bytes());
}

fn put32(out: &mut Vec<u8>, x: u32) {
    out.extend_from_slice(&x.to_le_bytes());
}

fn put64(out: &mut Vec<u8>, x: u64) {
    out.extend_from_slice(&x.to_le_bytes());
}

#[cfg(test)]
mod tests {
    use super::*;

    /// NEP 1: magic, version, little-endian length, the dictionary, spaces,
    /// a newline, and a total that is a multiple of 64.
    #[test]
    fn npy_headers_are_aligned_and_end_in_a_newline() {
        let h = npy_header("<f8", "(3, 2)");
        assert_eq!(&h[..8], b"\x93NUMPY\x01\x00");
        assert_eq!(h.len() % 64, 0);
        assert_eq!(usize::from(u16::from_le_bytes([h[8], h[9]])), h.len() - 10);
        assert_eq!(h.last(), Some(&b'\n'));
        let text = std::str::from_utf8(&h[10..]).expect("ASCII");
        assert!(text.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': (3, 2), }"));
    }

    /// What [`Npz`] writes, [`read`] reads back: the names and the rows.
    #[test]
    fn an_archive_reads_back() {
        let names: Vec<String> = ["t", "u:é.x"].map(String::from).to_vec();
        let (mut npz, mut bytes) = Npz::head(&names);
        let rows = [[0.0, 1.5], [0.1, -2.25]];
        let mut data = Vec::new();
        for row in rows {
            Npz::encode(row.into_iter(), &mut data);
        }
        npz.written(&data);
        bytes.extend_from_slice(&data);
        let path = std::env::temp_dir().join(format!("mstar-npz-{}.npz", std::process::id()));
        std::fs::write(&path, &bytes).expect("written");
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&path)
            .expect("open");
        npz.finish(&mut file, 2, false).expect("finished");
        drop(file);
        let (got_names, got) = read(&path).expect("read back");
        let _ = std::fs::remove_file(&path);
        assert_eq!(got_names, names);
        assert_eq!(got, vec![0.0, 1.5, 0.1, -2.25]);
    }

    /// A layout's head ends where its rows begin, and its row count has
    /// room for any number of rows without moving the rows.
    #[test]
    fn the_row_count_is_patched_in_place() {
        let names: Vec<String> = ["t", "u:x"].map(String::from).to_vec();
        let (npz, head) = Npz::head(&names);
        assert_eq!(head.len() as u64, npz.rows_at());
        let longest = npy_header("<f8", &format!("({}, 2)", u64::MAX));
        assert_eq!(longest.len(), npz.npy_len);
    }
}
