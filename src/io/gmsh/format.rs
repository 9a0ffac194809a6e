//! The byte-level reading of a `.msh` file: the `$MeshFormat` header, the storage (ASCII or
//! binary, the `size_t` size, the byte order), the node tags of `$Nodes` in file order,
//! `$PhysicalNames`, and the `mshio` parser run with its errors (and panics) turned into
//! one-line messages.

use std::collections::HashMap;

use super::Reader;
use crate::error::Result;

/// How the file stores its data, from the `$MeshFormat` line (checked by
/// `Reader::check_header`): binary or not, and the size of a `size_t`.
pub(super) fn storage(bytes: &[u8]) -> (bool, usize) {
    let format: Vec<String> = bytes
        .split(|&b| b == b'\n')
        .map(|l| String::from_utf8_lossy(l).trim().to_string())
        .skip_while(|l| l != "$MeshFormat")
        .nth(1)
        .map(|l| l.split_whitespace().map(str::to_string).collect())
        .unwrap_or_default();
    let binary = format.get(1).is_some_and(|t| t == "1");
    let size_t = format.get(2).and_then(|d| d.parse().ok()).unwrap_or(8);
    (binary, size_t)
}

/// Lines of the ASCII prologue of a file (up to the first section with binary content).
fn prologue_lines(bytes: &[u8]) -> impl Iterator<Item = &str> {
    bytes
        .split(|&b| b == b'\n')
        .map(|l| std::str::from_utf8(l).unwrap_or("").trim())
        .take_while(|l| {
            !matches!(
                *l,
                "$Entities" | "$Nodes" | "$Elements" | "$PartitionedEntities"
            )
        })
}

impl Reader {
    /// Checks `$MeshFormat`: version 4.1, file type 0 or 1, a supported size_t size.
    pub(super) fn check_header(&self, bytes: &[u8]) -> Result<()> {
        let mut lines = bytes
            .split(|&b| b == b'\n')
            .map(|l| String::from_utf8_lossy(l).trim().to_string())
            .skip_while(|l| l.is_empty());
        match lines.next() {
            None => return Err(self.err("file is empty (truncated?)")),
            Some(l) if l == "$MeshFormat" => {}
            Some(_) => return Err(self.err("not a Gmsh file: it does not start with $MeshFormat")),
        }
        let Some(header) = lines.next() else {
            return Err(self.err("file is truncated inside $MeshFormat"));
        };
        let fields: Vec<&str> = header.split_whitespace().collect();
        if fields.len() != 3 {
            return Err(self.err(format!(
                "bad $MeshFormat line '{header}' (expected 'version file-type data-size')"
            )));
        }
        if fields[0].parse::<f64>().ok() != Some(4.1) {
            return Err(self.err(format!(
                "MSH format version {} is not supported, only 4.1 (export with Mesh.MshFileVersion = 4.1)",
                fields[0]
            )));
        }
        if !matches!(fields[1], "0" | "1") {
            return Err(self.err(format!(
                "bad file type {} in $MeshFormat (0 = ASCII, 1 = binary)",
                fields[1]
            )));
        }
        if !matches!(fields[2], "4" | "8") {
            return Err(self.err(format!(
                "unsupported data size {} in $MeshFormat (4 or 8)",
                fields[2]
            )));
        }
        Ok(())
    }

    /// The node tags of `$Nodes` in file order, for blocks of `counts` nodes (as `mshio` read
    /// them). `mshio` keeps a block's tags only when the file's tags are not dense, and then
    /// in a map, where a repeated tag overwrites; a file whose dense tags are not in order, or
    /// that repeats a tag, would be misread. So the tags are read here, in ASCII as in binary
    /// (`stored`: binary or not and the `size_t` size, from [`storage`]; `int` of 4 bytes,
    /// coordinates of 8).
    pub(super) fn node_tags(
        &self,
        bytes: &[u8],
        (binary, size_t): (bool, usize),
        counts: &[usize],
    ) -> Result<Vec<u64>> {
        let bad = || self.err("cannot read the node tags of $Nodes");
        // The section's first line, "$Nodes" (with a CR in a file of CRLF lines).
        let start = [&b"$Nodes\n"[..], &b"$Nodes\r\n"[..]]
            .iter()
            .find_map(|marker| {
                bytes
                    .windows(marker.len())
                    .enumerate()
                    .find(|(i, w)| w == marker && (*i == 0 || bytes[i - 1] == b'\n'))
                    .map(|(i, _)| i + marker.len())
            })
            .ok_or_else(bad)?;
        let body = &bytes[start..];
        let total: usize = counts.iter().sum();
        let mut tags = Vec::with_capacity(total);
        if binary {
            let unsigned = |at: usize| -> Option<u64> {
                let b = body.get(at..at + size_t)?;
                Some(match size_t {
                    4 => u64::from(u32::from_le_bytes(b.try_into().ok()?)),
                    _ => u64::from_le_bytes(b.try_into().ok()?),
                })
            };
            // The header: 4 size_t; each block: 3 int, a size_t count, the tags, 3 doubles each.
            let mut at = 4 * size_t;
            for &n in counts {
                at += 3 * 4 + size_t;
                for k in 0..n {
                    tags.push(unsigned(at + k * size_t).ok_or_else(bad)?);
                }
                at += n * size_t + 3 * 8 * n;
            }
        } else {
            let mut words = std::str::from_utf8(body)
                .map_err(|_| bad())?
                .split_ascii_whitespace();
            // The header: 4 numbers; each block: 4 numbers, the tags, 3 coordinates each.
            words.nth(3).ok_or_else(bad)?;
            for &n in counts {
                words.nth(3).ok_or_else(bad)?;
                for _ in 0..n {
                    tags.push(words.next().and_then(|w| w.parse().ok()).ok_or_else(bad)?);
                }
                if n > 0 {
                    words.nth(3 * n - 1).ok_or_else(bad)?;
                }
            }
        }
        Ok(tags)
    }

    /// True when the binary file's check integer (the `int` 1 after the `$MeshFormat` line)
    /// reads 1 in little-endian order, the order [`Reader::node_tags`] reads.
    pub(super) fn little_endian(&self, bytes: &[u8]) -> bool {
        let Some(mut at) = bytes
            .windows(11)
            .position(|w| w == b"$MeshFormat".as_slice())
        else {
            return false;
        };
        // Past the end of the "$MeshFormat" line and of the "4.1 1 8" line.
        for _ in 0..2 {
            let Some(end) = bytes[at..].iter().position(|&b| b == b'\n') else {
                return false;
            };
            at += end + 1;
        }
        bytes
            .get(at..at + 4)
            .is_some_and(|b| b == 1i32.to_le_bytes().as_slice())
    }

    /// `$PhysicalNames`: `(dim, tag) -> name`.
    pub(super) fn physical_names(&self, bytes: &[u8]) -> Result<HashMap<(i32, i32), String>> {
        let mut names = HashMap::new();
        let mut lines = prologue_lines(bytes).skip_while(|l| *l != "$PhysicalNames");
        if lines.next().is_none() {
            return Ok(names);
        }
        let count: usize = lines
            .next()
            .and_then(|l| l.parse().ok())
            .ok_or_else(|| self.err("bad count in $PhysicalNames"))?;
        for _ in 0..count {
            let line = lines
                .next()
                .ok_or_else(|| self.err("file is truncated inside $PhysicalNames"))?;
            let mut it = line.splitn(3, char::is_whitespace);
            let bad = || self.err(format!("bad $PhysicalNames line '{line}'"));
            let dim: i32 = it.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
            let tag: i32 = it
                .next()
                .and_then(|s| s.trim().parse().ok())
                .ok_or_else(bad)?;
            let quoted = it.next().ok_or_else(bad)?.trim();
            // A name in double quotes (as gmsh writes it), or bare.
            let name = match quoted.strip_prefix('"') {
                Some(rest) => rest.strip_suffix('"').ok_or_else(bad)?,
                None => quoted,
            }
            .to_string();
            names.insert((dim, tag), name);
        }
        match lines.next() {
            Some("$EndPhysicalNames") => Ok(names),
            _ => Err(self.err("$PhysicalNames: missing $EndPhysicalNames after the names")),
        }
    }

    /// Runs `mshio`, turning its errors (and, defensively, panics) into messages.
    pub(super) fn parse(&self, bytes: &[u8]) -> Result<mshio::MshFile<u64, i32, f64>> {
        // mshio panics on some malformed headers: silence the default hook so the panic
        // becomes our one-line error, not a message plus a backtrace note.
        let hook = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
        let parsed = std::panic::catch_unwind(|| {
            mshio::parse_msh_bytes(bytes).map_err(|e| {
                let trace = e.filtered_backtrace();
                let Some((at, kind)) = trace.first() else {
                    return "unknown parse error".to_string();
                };
                let offset = bytes.len() - at.len();
                let line = bytes[..offset].iter().filter(|&&b| b == b'\n').count() + 1;
                let contexts: Vec<String> = trace[1..]
                    .iter()
                    .rev()
                    .map(|(_, k)| {
                        k.context()
                            .map(str::to_string)
                            .unwrap_or_else(|| k.to_string())
                    })
                    .collect();
                let truncated = !at.windows(4).any(|w| w == b"$End");
                format!(
                    "{}{}: {} (byte {offset}, line {line})",
                    if truncated {
                        "file is truncated: "
                    } else {
                        "cannot parse "
                    },
                    contexts.join(" > "),
                    kind
                )
            })
        });
        std::panic::set_hook(hook);
        match parsed {
            Ok(Ok(f)) => Ok(f),
            Ok(Err(msg)) => Err(self.err(msg)),
            Err(_) => Err(self.err("the MSH parser failed (malformed file)")),
        }
    }
}
