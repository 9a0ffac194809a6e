//! Machine-made bad inputs: case files and Gmsh meshes (ASCII and binary) mutated at random
//! (byte flips, truncations, lines deleted, repeated or swapped, numbers replaced by huge,
//! negative, fractional or non-finite ones, values replaced by values of other types, binary
//! counts overwritten) go through the reading and validation path of `mortar check`
//! (`Scene::load`) in-process: none may panic or take longer than [`LIMIT`], and every one
//! refused is refused in one line. A smaller sample (one in 50, 20 to 200) goes through the
//! binary.
//!
//! The count is `MUTATIONS` (default [`DEFAULT_COUNT`]); `ci/mutate` runs the full form.

mod common;

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use mortar::case::Scene;

/// Inputs of the reduced form (CI).
const DEFAULT_COUNT: usize = 3000;

/// The longest one input may take to be read and validated.
const LIMIT: Duration = Duration::from_secs(20);

/// xorshift64: the same inputs on every run for a seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Numbers that a reader must bound or refuse. (Not the moderately large ones: a mesh of a
/// few million elements is valid, and slow to build rather than wrong.)
const HOSTILE_NUMBERS: [&str; 21] = [
    "0",
    "-1",
    "-0.0",
    "1e308",
    "-1e308",
    "1e-308",
    "1e999",
    "nan",
    "inf",
    "-inf",
    "2147483647",
    "2147483648",
    "4294967296",
    "9223372036854775807",
    "18446744073709551616",
    "999999999",
    "1.5",
    "0.5",
    "3",
    "1e6",
    "-2147483649",
];

/// Values of other types.
const HOSTILE_VALUES: [&str; 10] = [
    "\"text\"",
    "\"\"",
    "true",
    "[]",
    "[1, 2]",
    "[\"a\", \"b\", \"c\"]",
    "{}",
    "{ kind = \"table\" }",
    "[[0.0, 1.0], [1.0]]",
    "1979-05-27",
];

/// One input: its case file and, for a Gmsh scene, its mesh.
#[derive(Clone)]
struct Input {
    case: Vec<u8>,
    mesh: Option<Vec<u8>>,
    /// What was done, to reproduce a failure.
    what: String,
}

/// A seed: a valid scene, with the folder of the files it refers to.
struct Seed {
    name: String,
    case: Vec<u8>,
    mesh: Option<Vec<u8>>,
    folder: Option<PathBuf>,
}

fn seeds() -> Vec<Seed> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut seeds = Vec::new();
    let mut cases: Vec<PathBuf> = std::fs::read_dir(root.join("cases"))
        .unwrap()
        .map(|e| e.unwrap().path().join("case.toml"))
        .filter(|p| p.exists())
        .collect();
    cases.push(root.join("cases/refinement/hex8_1.toml"));
    cases.sort();
    for path in cases {
        seeds.push(Seed {
            name: path.display().to_string(),
            case: std::fs::read(&path).unwrap(),
            mesh: None,
            folder: path.parent().map(Path::to_path_buf),
        });
    }
    for (mesh, bodies) in [
        ("two_hex.msh", &["left", "physical_6"][..]),
        ("tet10.msh", &["physical_1"][..]),
        ("two_bodies_binary.msh", &["left", "right"][..]),
    ] {
        let mut case = String::from("[[mesh]]\ngenerator = \"gmsh\"\nfile = \"mesh.msh\"\n");
        for body in bodies {
            case += &format!(
                "\n[[material]]\nbody = \"{body}\"\nmodel = \"neo_hookean\"\n\
                 young = 1000.0\npoisson = 0.3\n"
            );
        }
        seeds.push(Seed {
            name: format!("tests/data/{mesh}"),
            case: case.into_bytes(),
            mesh: Some(std::fs::read(root.join("tests/data").join(mesh)).unwrap()),
            folder: None,
        });
    }
    seeds
}

/// The spans of the numbers in `text` (digits with their sign, point and exponent).
fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let starts = text[i].is_ascii_digit()
            || (matches!(text[i], b'-' | b'+') && text.get(i + 1).is_some_and(u8::is_ascii_digit));
        if !starts || (i > 0 && (text[i - 1].is_ascii_alphanumeric() || text[i - 1] == b'_')) {
            i += 1;
            continue;
        }
        let start = i;
        i += 1;
        while i < text.len() && matches!(text[i], b'0'..=b'9' | b'.' | b'e' | b'E' | b'-' | b'+') {
            i += 1;
        }
        spans.push((start, i));
    }
    spans
}

/// Line spans (ends exclusive of the newline).
fn lines(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = 0;
    for (i, &b) in text.iter().enumerate() {
        if b == b'\n' {
            spans.push((start, i));
            start = i + 1;
        }
    }
    if start < text.len() {
        spans.push((start, text.len()));
    }
    spans
}

fn splice(text: &[u8], (a, b): (usize, usize), with: &[u8]) -> Vec<u8> {
    [&text[..a], with, &text[b..]].concat()
}

/// One random mutation of `text`; `binary`: the text holds binary sections.
fn mutate(text: &[u8], rng: &mut Rng, binary: bool) -> (Vec<u8>, String) {
    if text.is_empty() {
        return (b"x".to_vec(), "empty -> x".into());
    }
    let kinds = if binary { 8 } else { 7 };
    match rng.below(kinds) {
        0 => {
            let at = rng.below(text.len());
            let byte = rng.next() as u8;
            let mut out = text.to_vec();
            out[at] = byte;
            (out, format!("byte {at} = {byte:#04x}"))
        }
        1 => {
            let at = rng.below(text.len());
            (text[..at].to_vec(), format!("truncated at {at}"))
        }
        2 | 3 | 6 => {
            let ls = lines(text);
            let k = rng.below(ls.len());
            let (a, b) = ls[k];
            let end = (b + 1).min(text.len());
            match rng.below(3) {
                0 => (splice(text, (a, end), b""), format!("line {k} deleted")),
                1 => {
                    let line = text[a..end].to_vec();
                    let with = [line.as_slice(), line.as_slice()].concat();
                    (splice(text, (a, end), &with), format!("line {k} repeated"))
                }
                _ => {
                    let j = rng.below(ls.len());
                    let (c, d) = ls[j];
                    let (first, second) = if k < j { (k, j) } else { (j, k) };
                    let (lo, hi) = if k < j {
                        ((a, b), (c, d))
                    } else {
                        ((c, d), (a, b))
                    };
                    if first == second {
                        return (text.to_vec(), "unchanged".into());
                    }
                    let out = [
                        &text[..lo.0],
                        &text[hi.0..hi.1],
                        &text[lo.1..hi.0],
                        &text[lo.0..lo.1],
                        &text[hi.1..],
                    ]
                    .concat();
                    (out, format!("lines {first} and {second} swapped"))
                }
            }
        }
        4 => {
            let spans = numbers(text);
            if spans.is_empty() {
                return (text.to_vec(), "no number".into());
            }
            let span = *rng.pick(&spans);
            let with = *rng.pick(&HOSTILE_NUMBERS);
            (
                splice(text, span, with.as_bytes()),
                format!("number at {} = {with}", span.0),
            )
        }
        5 => {
            let spans = numbers(text);
            let eq: Vec<(usize, usize)> = lines(text)
                .into_iter()
                .filter_map(|(a, b)| {
                    let at = text[a..b].iter().position(|&c| c == b'=')?;
                    Some((a + at + 1, b))
                })
                .collect();
            let with = *rng.pick(&HOSTILE_VALUES);
            if let Some(&span) = (!eq.is_empty()).then(|| rng.pick(&eq)) {
                (
                    splice(text, span, format!(" {with}").as_bytes()),
                    format!("value at {} = {with}", span.0),
                )
            } else if let Some(&span) = (!spans.is_empty()).then(|| rng.pick(&spans)) {
                (
                    splice(text, span, with.as_bytes()),
                    format!("number at {} = {with}", span.0),
                )
            } else {
                (text.to_vec(), "no value".into())
            }
        }
        _ => {
            // A binary count or tag overwritten (4 or 8 bytes).
            let width = if rng.below(2) == 0 { 4 } else { 8 };
            if text.len() < width {
                return (text.to_vec(), "too short".into());
            }
            let at = rng.below(text.len() - width + 1);
            let values: [u64; 6] = [0, 1, u64::MAX, i32::MAX as u64, 1 << 40, 0x8000_0000];
            let v = *rng.pick(&values);
            let mut out = text.to_vec();
            out[at..at + width].copy_from_slice(&v.to_le_bytes()[..width]);
            (out, format!("{width} bytes at {at} = {v:#x}"))
        }
    }
}

/// Input `k` of the sequence: a seed and one to three mutations of its case file or mesh.
fn input(seeds: &[Seed], k: usize) -> (usize, Input) {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ (k as u64 + 1).wrapping_mul(0x2545_F491_4F6C_DD1D));
    let s = rng.below(seeds.len());
    let seed = &seeds[s];
    let mut input = Input {
        case: seed.case.clone(),
        mesh: seed.mesh.clone(),
        what: String::new(),
    };
    let rounds = 1 + rng.below(3);
    let mut steps = Vec::new();
    for _ in 0..rounds {
        let on_mesh = input.mesh.is_some() && rng.below(4) != 0;
        if on_mesh {
            let mesh = input.mesh.as_ref().unwrap();
            let binary = mesh.windows(7).any(|w| w == b"4.1 1 8");
            let (m, what) = mutate(mesh, &mut rng, binary);
            input.mesh = Some(m);
            steps.push(format!("mesh: {what}"));
        } else {
            let (c, what) = mutate(&input.case, &mut rng, false);
            input.case = c;
            steps.push(format!("case: {what}"));
        }
    }
    input.what = format!("input {k} from {}: {}", seed.name, steps.join("; "));
    (s, input)
}

/// A folder per seed, with the files its case refers to, where the mutated files go.
fn folders(seeds: &[Seed], name: &str) -> Vec<PathBuf> {
    let base = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    seeds
        .iter()
        .enumerate()
        .map(|(i, seed)| {
            let dir = base.join(format!("seed{i}"));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            if let Some(folder) = &seed.folder {
                for entry in std::fs::read_dir(folder).unwrap() {
                    let path = entry.unwrap().path();
                    if path.is_file() {
                        std::fs::copy(&path, dir.join(path.file_name().unwrap())).unwrap();
                    }
                }
            }
            dir
        })
        .collect()
}

/// Writes `input` into `dir`; the case file's path.
fn write(input: &Input, dir: &Path) -> PathBuf {
    let case = dir.join("mutated.toml");
    std::fs::write(&case, &input.case).unwrap();
    if let Some(mesh) = &input.mesh {
        std::fs::write(dir.join("mesh.msh"), mesh).unwrap();
    }
    case
}

/// What reading one input came to.
enum Verdict {
    Valid,
    Refused(String),
    Panicked(String),
}

fn read(case: &Path) -> Verdict {
    match std::panic::catch_unwind(|| Scene::load(case)) {
        Ok(Ok(_)) => Verdict::Valid,
        Ok(Err(e)) => Verdict::Refused(e.to_string()),
        Err(payload) => Verdict::Panicked(
            payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default(),
        ),
    }
}

#[test]
fn mutated_inputs_never_panic_or_hang_and_are_refused_in_one_line() {
    let count = std::env::var("MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_COUNT);
    let seeds = seeds();
    let dirs = folders(&seeds, "mutated_inputs");
    for (seed, dir) in seeds.iter().zip(&dirs) {
        let unmutated = Input {
            case: seed.case.clone(),
            mesh: seed.mesh.clone(),
            what: String::new(),
        };
        if let Verdict::Refused(e) | Verdict::Panicked(e) = read(&write(&unmutated, dir)) {
            panic!("seed {} is not valid: {e}", seed.name);
        }
    }
    // One worker reads; this thread watches the time of each input.
    let (jobs, job_rx) = mpsc::channel::<PathBuf>();
    let (verdict_tx, verdicts) = mpsc::channel::<Verdict>();
    std::panic::set_hook(Box::new(|_| {}));
    std::thread::spawn(move || {
        for case in job_rx {
            if verdict_tx.send(read(&case)).is_err() {
                break;
            }
        }
    });
    let (mut valid, mut refused, mut failures) = (0, 0, Vec::new());
    for k in 0..count {
        let (s, input) = input(&seeds, k);
        jobs.send(write(&input, &dirs[s])).unwrap();
        match verdicts.recv_timeout(LIMIT) {
            Ok(Verdict::Valid) => valid += 1,
            Ok(Verdict::Refused(line)) if !line.trim().is_empty() && !line.contains('\n') => {
                refused += 1
            }
            Ok(Verdict::Refused(line)) => {
                failures.push(format!("{}: refused not in one line:\n{line}", input.what))
            }
            Ok(Verdict::Panicked(message)) => {
                failures.push(format!("{}: panicked: {message}", input.what))
            }
            Err(_) => {
                let _ = std::panic::take_hook();
                panic!("{}: not read within {LIMIT:?}", input.what);
            }
        }
    }
    let _ = std::panic::take_hook();
    eprintln!(
        "{count} mutated inputs: {refused} refused in one line, {valid} valid, {} failures",
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{} of {count} inputs failed; the first:\n{}",
        failures.len(),
        failures[..failures.len().min(10)].join("\n")
    );
    assert!(
        refused > count / 2,
        "most mutations should be refused: {refused} of {count}"
    );
    check_through_the_binary(&seeds, (count / 50).clamp(20, 200));
}

/// A sample through the binary: `mortar check` exits 0 or 1 (never a panic's 101 or a
/// signal), and a refusal is one line on stderr.
fn check_through_the_binary(seeds: &[Seed], count: usize) {
    let dirs = folders(seeds, "mutated_binary");
    for k in 0..count {
        let (s, input) = input(seeds, 1_000_000 + k);
        let case = write(&input, &dirs[s]);
        let out = common::mortar_command()
            .arg("check")
            .arg(&case)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        match out.status.code() {
            Some(0) => {}
            Some(1) => {
                let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
                assert_eq!(lines.len(), 1, "{}: {stderr}", input.what);
                assert!(
                    lines[0].starts_with("mortar: error:"),
                    "{}: {stderr}",
                    input.what
                );
            }
            other => panic!("{}: exit {other:?}: {stderr}", input.what),
        }
    }
}
