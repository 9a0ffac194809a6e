//! The checkpoint file: named arrays of numbers and texts, bit-exact, with a checksum.
//!
//! A checkpoint holds everything a restarted run needs to go on as if it had never stopped
//! (`solver::checkpoint` decides what; the model's contributions write their own part through
//! [`crate::model::StateSink`]). This layer only stores and reads back records:
//!
//! ```text
//! "mortar checkpoint\n"                 18 bytes
//! format version                        u32
//! records, each:
//!   kind                                u8: 1 f64 array, 2 u64 array, 3 UTF-8 text
//!   name length, name                   u16, bytes
//!   count                               u64 (values, or bytes of the text)
//!   payload                             count x 8 bytes (little endian), or the text
//! end:                                  u8 0, then the FNV-1a 64 checksum (u64) of every byte
//!                                       before it
//! ```
//!
//! Numbers are stored as their bits, so a restart reads back exactly what was written. A
//! reader takes the records in the order they were written and names the one it expected when
//! the file holds another: a file of another layout is refused rather than misread. A file cut
//! short or altered fails its checksum before anything is read from it.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::model::{StateSink, StateSource};

const MAGIC: &[u8; 18] = b"mortar checkpoint\n";

/// The layout of the records; a checkpoint of another format version is refused.
pub const FORMAT_VERSION: u32 = 2;

const F64S: u8 = 1;
const U64S: u8 = 2;
const TEXT: u8 = 3;
const END: u8 = 0;

/// The FNV-1a 64-bit hash: the checkpoint's checksum, and the digests that tie a checkpoint to
/// its case (stable across builds and platforms, unlike the standard library's hasher).
#[derive(Clone, Copy, Debug)]
pub struct Fnv64(u64);

impl Default for Fnv64 {
    fn default() -> Self {
        Fnv64(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv64 {
    pub fn bytes(&mut self, bytes: &[u8]) -> &mut Self {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
        self
    }

    pub fn finish(&self) -> u64 {
        self.0
    }

    /// The hash of `value`'s `Debug` text, streamed (no copy of the text is made).
    pub fn of_debug(value: &impl std::fmt::Debug) -> u64 {
        use std::fmt::Write;
        let mut h = Fnv64::default();
        let _ = write!(h, "{value:?}");
        h.finish()
    }
}

impl std::fmt::Write for Fnv64 {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.bytes(s.as_bytes());
        Ok(())
    }
}

/// A checkpoint being written: records appended in order, then [`Writer::finish`].
pub struct Writer {
    bytes: Vec<u8>,
}

impl Default for Writer {
    fn default() -> Self {
        let mut bytes = MAGIC.to_vec();
        bytes.extend(FORMAT_VERSION.to_le_bytes());
        Writer { bytes }
    }
}

impl Writer {
    fn header(&mut self, kind: u8, name: &str, count: usize) {
        let name = &name.as_bytes()[..name.len().min(u16::MAX as usize)];
        self.bytes.push(kind);
        self.bytes.extend((name.len() as u16).to_le_bytes());
        self.bytes.extend(name);
        self.bytes.extend((count as u64).to_le_bytes());
    }

    /// Appends the text record `name`.
    pub fn text(&mut self, name: &str, text: &str) {
        self.header(TEXT, name, text.len());
        self.bytes.extend(text.as_bytes());
    }

    /// The finished file: the records, the end mark and the checksum.
    pub fn finish(mut self) -> Vec<u8> {
        self.bytes.push(END);
        let sum = Fnv64::default().bytes(&self.bytes).finish();
        self.bytes.extend(sum.to_le_bytes());
        self.bytes
    }
}

impl Writer {
    /// Appends a record of `kind` holding `words`, each eight little-endian bytes.
    fn words(&mut self, kind: u8, name: &str, words: impl ExactSizeIterator<Item = [u8; 8]>) {
        self.header(kind, name, words.len());
        self.bytes.reserve(8 * words.len());
        words.for_each(|w| self.bytes.extend(w));
    }
}

impl StateSink for Writer {
    fn f64s(&mut self, name: &str, values: &[f64]) {
        self.words(F64S, name, values.iter().map(|v| v.to_le_bytes()));
    }

    fn u64s(&mut self, name: &str, values: &[u64]) {
        self.words(U64S, name, values.iter().map(|v| v.to_le_bytes()));
    }
}

/// A checkpoint being read back, record by record in the order written.
pub struct Reader {
    path: PathBuf,
    bytes: Vec<u8>,
    at: usize,
}

impl Reader {
    /// Reads and checks the file at `path`: its magic, format version and checksum.
    pub fn open(path: &Path) -> Result<Reader> {
        let bytes = std::fs::read(path).map_err(|e| {
            Error::Restart(format!(
                "cannot read checkpoint file {}: {e}",
                path.display()
            ))
        })?;
        Reader::from_bytes(path, bytes)
    }

    /// Checks `bytes` read from `path` (named in the errors).
    pub fn from_bytes(path: &Path, bytes: Vec<u8>) -> Result<Reader> {
        let bad = |what: &str| Error::Restart(format!("checkpoint file {} {what}", path.display()));
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err(bad("is not a mortar checkpoint"));
        }
        let body = bytes.len().saturating_sub(8);
        if body < MAGIC.len() + 5 || bytes[body - 1] != END {
            return Err(bad("is truncated"));
        }
        let sum = u64::from_le_bytes(bytes[body..].try_into().expect("8 bytes"));
        if Fnv64::default().bytes(&bytes[..body]).finish() != sum {
            return Err(bad("is damaged or truncated (its checksum does not match)"));
        }
        let version = u32::from_le_bytes(bytes[18..22].try_into().expect("4 bytes"));
        if version != FORMAT_VERSION {
            return Err(bad(&format!(
                "has format version {version}; this program reads version {FORMAT_VERSION}"
            )));
        }
        Ok(Reader {
            path: path.to_path_buf(),
            bytes,
            at: MAGIC.len() + 4,
        })
    }

    fn error(&self, msg: String) -> Error {
        Error::Restart(format!("checkpoint file {}: {msg}", self.path.display()))
    }

    /// The next record's payload, which must be `name` of `kind`, `width` bytes per item.
    fn record(&mut self, kind: u8, name: &str, width: usize) -> Result<&[u8]> {
        let b = &self.bytes;
        let end = b.len() - 9;
        let take = |at: &mut usize, n: usize| -> Option<std::ops::Range<usize>> {
            let r = *at..at.checked_add(n)?;
            (r.end <= end).then(|| {
                *at = r.end;
                r
            })
        };
        let mut at = self.at;
        let head = take(&mut at, 3).map(|r| {
            (
                b[r.start],
                u16::from_le_bytes([b[r.start + 1], b[r.start + 2]]),
            )
        });
        let found = head.and_then(|(k, len)| {
            let name = take(&mut at, usize::from(len))?;
            let count = take(&mut at, 8)?;
            let count = u64::from_le_bytes(b[count].try_into().expect("8 bytes"));
            let size = usize::try_from(count).ok()?.checked_mul(width)?;
            Some((k, name, take(&mut at, size)?))
        });
        match found {
            Some((k, n, payload)) if k == kind && &b[n.clone()] == name.as_bytes() => {
                self.at = at;
                Ok(&self.bytes[payload])
            }
            Some((_, n, _)) => {
                let other = String::from_utf8_lossy(&b[n]).into_owned();
                Err(self.error(format!("expected the record '{name}', found '{other}'")))
            }
            None => Err(self.error(format!("expected the record '{name}', found the end"))),
        }
    }

    /// The text record `name`.
    pub fn text(&mut self, name: &str) -> Result<String> {
        let raw = self.record(TEXT, name, 1)?.to_vec();
        String::from_utf8(raw).map_err(|_| self.error(format!("record '{name}' is not text")))
    }

    /// Whether every record has been read.
    pub fn at_end(&self) -> bool {
        self.at == self.bytes.len() - 9
    }
}

impl Reader {
    /// The next record, `name` of `kind`, as eight-byte words.
    fn words(&mut self, kind: u8, name: &str) -> Result<impl Iterator<Item = [u8; 8]> + '_> {
        let raw = self.record(kind, name, 8)?;
        Ok(raw.chunks_exact(8).map(|c| c.try_into().expect("8 bytes")))
    }
}

impl StateSource for Reader {
    fn f64s(&mut self, name: &str) -> Result<Vec<f64>> {
        Ok(self.words(F64S, name)?.map(f64::from_le_bytes).collect())
    }

    fn u64s(&mut self, name: &str) -> Result<Vec<u64>> {
        Ok(self.words(U64S, name)?.map(u64::from_le_bytes).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<u8> {
        let mut w = Writer::default();
        w.text("case", "sliding blocks");
        w.f64s("x", &[0.1 + 0.2, -0.0, f64::MIN_POSITIVE, 1e308]);
        w.u64s("n", &[u64::MAX, 0, 7]);
        w.f64s("empty", &[]);
        w.finish()
    }

    /// Every value comes back bit for bit, in order; a record read out of order names both.
    #[test]
    fn records_come_back_exactly() {
        let p = Path::new("c.bin");
        let mut r = Reader::from_bytes(p, sample()).unwrap();
        assert_eq!(r.text("case").unwrap(), "sliding blocks");
        let x = r.f64s("x").unwrap();
        let bits: Vec<u64> = x.iter().map(|v| v.to_bits()).collect();
        let want = [0.1 + 0.2, -0.0, f64::MIN_POSITIVE, 1e308].map(f64::to_bits);
        assert_eq!(bits, want);
        let e = r.f64s("m").unwrap_err().to_string();
        assert!(e.contains("expected the record 'm', found 'n'"), "{e}");
        assert_eq!(r.u64s("n").unwrap(), vec![u64::MAX, 0, 7]);
        assert!(r.f64s("empty").unwrap().is_empty());
        assert!(r.at_end());
        let e = r.f64s("more").unwrap_err().to_string();
        assert!(e.contains("found the end"), "{e}");
    }

    /// A file cut anywhere, or with any byte changed, is refused with one line.
    #[test]
    fn truncated_or_altered_files_are_refused() {
        let p = Path::new("c.bin");
        let good = sample();
        for cut in 0..good.len() {
            let e = Reader::from_bytes(p, good[..cut].to_vec()).err().unwrap();
            let msg = e.to_string();
            assert!(!msg.contains('\n') && msg.contains("c.bin"), "{msg}");
        }
        for i in 0..good.len() {
            let mut bad = good.clone();
            bad[i] ^= 0x10;
            assert!(Reader::from_bytes(p, bad).is_err(), "byte {i}");
        }
        let mut other = Writer::default();
        other.u64s("n", &[1]);
        let mut r = Reader::from_bytes(p, other.finish()).unwrap();
        assert!(r.f64s("n").is_err());
    }
}
