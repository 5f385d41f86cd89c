//! Issue 12's seeded corruption campaign, run by `scripts/test.sh` after `cargo test`.
//!
//! For each input format — ROS 1 bags with `none`/`bz2`/`lz4` chunks, MCAP with
//! `none`/`zstd`/`lz4` chunks, and a rosbag2 sqlite3 bag directory — a small clean file is
//! written with the workspace's own writers (several chunks, an Imu topic and another
//! topic), its regions are mapped (header, chunk headers, chunk data, index records,
//! connection/schema/channel records, chunk infos/indexes, summary, footer, sqlite pages),
//! and `VARIANTS` corrupted copies are made from one seed: bit flips, byte runs, truncations
//! and index edits (counts and offsets set to 0, 0xFFFFFFFF, 0x08000000, ±1 or random).
//! Each copy goes through the real `bag2mat` binary in a child process with an address-space
//! limit and a timeout, and must end in one of:
//!
//! * **clean**: exit 0, the clean rows exactly;
//! * **altered**: exit 0, as many rows as the clean read but other values (a flipped payload
//!   bit in a format without checksums: nothing was lost);
//! * **warned**: exit 0 with a `warning:` that names what was lost (fewer rows never pass
//!   without one);
//! * **error**: exit 1 with one `bag2mat: error: …` line.
//!
//! Anything else fails the campaign: a panic or signal, a hang, an allocation past the
//! limit, fewer or more rows in silence, an exit code other than 0/1, an unclear error.
//! The last printed line gives the counts per format. `FUZZ_VARIANTS` changes the number of
//! variants per format (default 300), `FUZZ_SEED` the seed.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use bag2mat::bag::BagWriter;
use bag2mat::bag::record::{Header, Op, raw_record};
use bag2mat::imu_msg::Imu;
use bag2mat::mcap::ChunkCompression;
use bag2mat::rosbag2::{Ros2BagWriter, Storage};
use bag2mat::{Compression, RosTime};

/// The campaign's seed (every variant derives from it).
const SEED: u64 = 0x1212_2026_0000_0012;
/// Variants per format.
const VARIANTS: usize = 300;
/// Imu messages in each clean file (plus one other-topic message per 100).
const MESSAGES: u32 = 1000;
/// Chunk size of the clean files: ~20 messages per chunk, so every file has many chunks.
const CHUNK_BYTES: usize = 8 * 1024;
/// Address-space limit of each child: the clean matrix is 56 KB; threads, allocator arenas
/// and buffers fit easily, a count trusted to size memory does not.
const MEM_LIMIT_BYTES: u64 = 1 << 30;
/// A child still running after this is a hang.
const TIMEOUT: Duration = Duration::from_secs(20);

/// splitmix64: a small seeded generator (no dependency, same sequence everywhere).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

#[derive(Debug, Clone, Copy)]
enum Format {
    Ros1(Compression),
    Mcap(ChunkCompression),
    Db3,
}

impl Format {
    fn name(self) -> String {
        match self {
            Format::Ros1(c) => format!("ros1-{}", c.name()),
            Format::Mcap(ChunkCompression::None) => "mcap-none".into(),
            Format::Mcap(c) => format!("mcap-{}", c.name()),
            Format::Db3 => "db3".into(),
        }
    }
}

/// A named byte range of the file to corrupt.
#[derive(Debug, Clone)]
struct Region {
    kind: &'static str,
    range: std::ops::Range<usize>,
    /// Holds counts or offsets (index edits apply).
    index: bool,
}

/// A clean input: what to pass to bag2mat, which file to corrupt, and its regions.
struct Clean {
    input: PathBuf,
    file: PathBuf,
    regions: Vec<Region>,
    csv: String,
}

fn imu(i: u32) -> (u64, Imu) {
    let t = RosTime::from_nanos(1_700_000_000_000_000_000 + i as u64 * 5_000_000);
    let x = i as f64;
    (
        t.as_nanos(),
        Imu {
            seq: i,
            stamp: t,
            frame_id: "imu_link".into(),
            orientation: [0.0, 0.0, 0.0, 1.0],
            angular_velocity: [(x * 0.37).sin() * 1e-3, -x * 1e-7, 1.0 / (x + 3.0)],
            linear_acceleration: [(x * 0.11).cos() * 0.1, 0.01, 9.81 + x * 1e-9],
            ..Imu::default()
        },
    )
}

fn status(i: u32) -> Vec<u8> {
    bag2mat::test_tools::string_message(&format!("status {i}"))
}

fn write_ros1(path: &Path, c: Compression) {
    let mut w = BagWriter::create(path, c).expect("create bag");
    w.set_chunk_threshold(CHUNK_BYTES);
    let ci = w.add_imu_connection("imu");
    let cs = bag2mat::test_tools::add_string_connection(&mut w, "/status");
    for i in 0..MESSAGES {
        let (t, m) = imu(i);
        w.write_imu(ci, RosTime::from_nanos(t), &m).expect("write");
        if i % 100 == 0 {
            w.write_raw(cs, RosTime::from_nanos(t), &status(i))
                .expect("write");
        }
    }
    w.finish().expect("finish bag");
}

fn write_ros2(dir: &Path, storage: Storage) {
    let mut w = Ros2BagWriter::create(dir, storage).expect("create bag");
    w.set_mcap_chunk_size(CHUNK_BYTES);
    let ti = w.add_imu_topic("imu").expect("topic");
    let ts = w
        .add_topic(
            "/status",
            "std_msgs/msg/String",
            "string data",
            "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
        )
        .expect("topic");
    for i in 0..MESSAGES {
        let (t, m) = imu(i);
        w.write_imu(ti, t, &m).expect("write");
        if i % 100 == 0 {
            let text = format!("status {i}\0");
            let mut d = vec![0u8, 1, 0, 0];
            d.extend_from_slice(&(text.len() as u32).to_le_bytes());
            d.extend_from_slice(text.as_bytes());
            w.write_raw(ts, t, &d).expect("write");
        }
    }
    w.finish().expect("finish bag");
}

/// Regions of a ROS 1 bag.
fn ros1_regions(b: &[u8]) -> Vec<Region> {
    let mut out = Vec::new();
    let mut pos = 13;
    let mut first = true;
    while let Some(r) = raw_record(b, pos) {
        let hs = pos + 4;
        let ds = hs + r.header.len() + 4;
        let op = Header::parse(r.header).ok().and_then(|h| h.op().ok());
        let mut push = |kind, range, index| out.push(Region { kind, range, index });
        match op {
            Some(Op::BagHeader) if first => push("header", pos..ds, true),
            Some(Op::Chunk) => {
                push("chunk header", pos..ds, true);
                push("chunk data", ds..r.end, false);
            }
            Some(Op::IndexData) => push("index data", pos..r.end, true),
            Some(Op::Connection) => push("connection", pos..r.end, false),
            Some(Op::ChunkInfo) => push("chunk info", pos..r.end, true),
            _ => {}
        }
        first = false;
        pos = r.end;
    }
    out
}

/// Regions of an MCAP file.
fn mcap_regions(b: &[u8]) -> Vec<Region> {
    let mut out = vec![Region {
        kind: "header",
        range: 0..8,
        index: false,
    }];
    let mut pos = 8;
    let mut summary = false;
    while pos + 9 <= b.len() {
        let op = b[pos];
        let len = u64::from_le_bytes(b[pos + 1..pos + 9].try_into().expect("8 bytes")) as usize;
        let end = pos + 9 + len;
        if end > b.len() {
            break;
        }
        let mut push = |kind, range, index| out.push(Region { kind, range, index });
        match op {
            0x01 => push("header", pos..end, false),
            0x06 => {
                // Chunk: 3×u64, u32 crc, compression string, u64 records length, records.
                let c = pos + 9;
                let slen = u32::from_le_bytes(b[c + 28..c + 32].try_into().expect("4")) as usize;
                let records = c + 32 + slen + 8;
                push("chunk header", pos..records, true);
                push("chunk data", records..end, false);
            }
            0x07 => push("message index", pos..end, true),
            0x03 | 0x04 if !summary => push("schema/channel", pos..end, false),
            0x0F => {
                summary = true;
                push("data end", pos..end, false);
            }
            0x02 => push("footer", pos..b.len(), true),
            _ if summary => push("summary", pos..end, true),
            _ => {}
        }
        pos = end;
    }
    out
}

/// Regions of a sqlite3 file: its header, the schema page, the data pages, the last page.
fn db3_regions(b: &[u8]) -> Vec<Region> {
    let page = match u16::from_be_bytes([b[16], b[17]]) {
        1 => 65536,
        n => n as usize,
    };
    let mut out = vec![
        Region {
            kind: "header",
            range: 0..100,
            index: true,
        },
        Region {
            kind: "schema page",
            range: 100..page,
            index: true,
        },
    ];
    let pages = b.len() / page;
    for p in 1..pages {
        out.push(Region {
            kind: if p + 1 == pages {
                "last page"
            } else {
                "data page"
            },
            range: p * page..(p + 1) * page,
            index: false,
        });
    }
    out
}

fn make_clean(dir: &Path, f: Format, bin: &Path) -> Clean {
    let name = f.name();
    let (input, file, regions) = match f {
        Format::Ros1(c) => {
            let p = dir.join(format!("{name}.bag"));
            write_ros1(&p, c);
            let r = ros1_regions(&std::fs::read(&p).expect("read"));
            (p.clone(), p, r)
        }
        Format::Mcap(c) => {
            let d = dir.join(&name);
            write_ros2(&d, Storage::Mcap(c));
            let p = d.join(format!("{name}_0.mcap"));
            let r = mcap_regions(&std::fs::read(&p).expect("read"));
            // The bare file: its own summary is the only promise.
            (p.clone(), p, r)
        }
        Format::Db3 => {
            let d = dir.join(&name);
            write_ros2(&d, Storage::Sqlite3);
            let p = d.join(format!("{name}_0.db3"));
            let r = db3_regions(&std::fs::read(&p).expect("read"));
            // The bag directory: metadata.yaml promises the counts.
            (d, p, r)
        }
    };
    let out = dir.join(format!("{name}.clean.csv"));
    let r = run_child(bin, &input, &out);
    assert!(
        r.code == Some(0) && r.stderr.is_empty(),
        "{name}: the clean file does not read cleanly: {r:?}"
    );
    let csv = std::fs::read_to_string(&out).expect("clean csv");
    assert_eq!(
        csv.lines().count(),
        MESSAGES as usize + 1,
        "{name}: clean rows"
    );
    Clean {
        input,
        file,
        regions,
        csv,
    }
}

#[derive(Debug)]
struct ChildRun {
    code: Option<i32>,
    signal: Option<i32>,
    timed_out: bool,
    stderr: String,
    /// Wall time of the child.
    elapsed: Duration,
}

fn run_child(bin: &Path, input: &Path, out: &Path) -> ChildRun {
    use std::os::unix::process::{CommandExt, ExitStatusExt};
    let _ = std::fs::remove_file(out);
    let mut cmd = Command::new(bin);
    cmd.arg(input)
        .arg("imu")
        .arg("-o")
        .arg(out)
        .args(["--format", "csv", "--quiet"])
        .env("RAYON_NUM_THREADS", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    // SAFETY: setrlimit is async-signal-safe and touches only the child.
    unsafe {
        cmd.pre_exec(|| {
            let lim = libc::rlimit {
                rlim_cur: MEM_LIMIT_BYTES,
                rlim_max: MEM_LIMIT_BYTES,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let mut child = cmd.spawn().expect("spawn bag2mat");
    let mut stderr = child.stderr.take().expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut stderr, &mut s);
        s
    });
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            timed_out = true;
            break child.wait().expect("wait");
        }
        std::thread::sleep(Duration::from_millis(1));
    };
    ChildRun {
        code: status.code(),
        signal: status.signal(),
        timed_out,
        stderr: reader.join().unwrap_or_default(),
        elapsed: start.elapsed(),
    }
}

/// How a variant ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Outcome {
    Clean,
    Altered,
    Warned,
    Error,
}

fn classify(clean: &Clean, r: &ChildRun, out: &Path) -> Result<Outcome, String> {
    if r.timed_out {
        return Err(format!("hang (killed after {TIMEOUT:?})"));
    }
    if let Some(s) = r.signal {
        return Err(format!("killed by signal {s}: {}", r.stderr.trim()));
    }
    if r.stderr.contains("panicked") || r.stderr.contains("memory allocation") {
        return Err(format!("panic or abort: {}", r.stderr.trim()));
    }
    match r.code {
        Some(0) => {}
        Some(1) => {
            let errors: Vec<&str> = r
                .stderr
                .lines()
                .filter(|l| l.starts_with("bag2mat: error: "))
                .collect();
            return if errors.len() == 1 {
                Ok(Outcome::Error)
            } else {
                Err(format!(
                    "exit 1 without one clear error line: {}",
                    r.stderr.trim()
                ))
            };
        }
        c => return Err(format!("exit code {c:?}: {}", r.stderr.trim())),
    }
    let csv = std::fs::read_to_string(out).map_err(|e| format!("exit 0 but no output: {e}"))?;
    if csv == clean.csv {
        return Ok(Outcome::Clean);
    }
    let (rows, want) = (csv.lines().count(), clean.csv.lines().count());
    let warned = r.stderr.lines().any(|l| {
        l.starts_with("warning: ")
            && ["lost", "skipped", "damaged", "unreadable", "could not"]
                .iter()
                .any(|w| l.contains(w))
    });
    if warned {
        return Ok(Outcome::Warned);
    }
    if rows == want {
        return Ok(Outcome::Altered);
    }
    Err(format!(
        "{} rows of {} in silence: {}",
        rows as i64 - 1,
        want - 1,
        r.stderr.trim()
    ))
}

/// Makes corrupted copy `v` of `bytes`; returns the new bytes and what was done.
fn mutate(bytes: &[u8], regions: &[Region], rng: &mut Rng, v: usize) -> (Vec<u8>, String) {
    let mut b = bytes.to_vec();
    // Cycle through the region kinds so that each gets its share.
    let mut kinds: Vec<&str> = regions.iter().map(|r| r.kind).collect();
    kinds.sort_unstable();
    kinds.dedup();
    let kind = kinds[v % kinds.len()];
    let of_kind: Vec<&Region> = regions.iter().filter(|r| r.kind == kind).collect();
    let reg = of_kind[rng.below(of_kind.len())];
    let (a, z) = (
        reg.range.start,
        reg.range.end.max(reg.range.start + 1).min(b.len()),
    );
    let at = a + rng.below(z - a);
    let op = rng.below(if reg.index { 4 } else { 3 });
    let what = match op {
        0 => {
            let n = 1 + rng.below(3);
            for _ in 0..n {
                let k = a + rng.below(z - a);
                b[k] ^= 1 << rng.below(8);
            }
            format!("{n} bit flip(s) in {kind} at {at}")
        }
        1 => {
            let len = (1 + rng.below(64)).min(b.len() - at);
            let fill = rng.below(3);
            for x in &mut b[at..at + len] {
                *x = match fill {
                    0 => 0,
                    1 => 0xFF,
                    _ => rng.next() as u8,
                };
            }
            format!("{len}-byte run in {kind} at {at}")
        }
        2 => {
            b.truncate(at);
            format!("truncated in {kind} at {at}")
        }
        _ => {
            let at = (at & !3).max(a);
            let old = u32::from_le_bytes(
                b.get(at..at + 4)
                    .and_then(|s| s.try_into().ok())
                    .unwrap_or([0; 4]),
            );
            let new = match rng.below(5) {
                0 => 0,
                1 => u32::MAX,
                2 => 0x0800_0000,
                3 => old.wrapping_add(if rng.below(2) == 0 { 1 } else { u32::MAX }),
                _ => rng.next() as u32,
            };
            let end = (at + 4).min(b.len());
            b[at..end].copy_from_slice(&new.to_le_bytes()[..end - at]);
            format!("index edit in {kind} at {at}: {old:#x} -> {new:#x}")
        }
    };
    (b, what)
}

#[derive(Default, Clone)]
struct Tally {
    clean: usize,
    altered: usize,
    warned: usize,
    error: usize,
    failed: usize,
    /// The slowest variant: (seconds, variant, what was done to it).
    slowest: Option<(f64, usize, String)>,
}

fn main() {
    let start = Instant::now();
    let variants: usize = std::env::var("FUZZ_VARIANTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(VARIANTS);
    let seed: u64 = std::env::var("FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(SEED);
    // The bag2mat binary built beside this example (target/<profile>/bag2mat).
    let exe = std::env::current_exe().expect("current exe");
    let bin = exe
        .parent()
        .and_then(|p| p.parent())
        .map(|p| p.join("bag2mat"))
        .expect("target dir");
    assert!(
        bin.exists(),
        "{} is missing: build it first (cargo build -p bag2mat)",
        bin.display()
    );
    // FUZZ_ONLY=FORMAT:VARIANT runs one variant and keeps it (for debugging).
    let only: Option<(String, usize)> = std::env::var("FUZZ_ONLY").ok().and_then(|v| {
        let (f, k) = v.split_once(':')?;
        Some((f.to_string(), k.parse().ok()?))
    });
    // FUZZ_VERBOSE=1 prints every variant that does not read clean.
    let verbose = std::env::var_os("FUZZ_VERBOSE").is_some();
    let dir = tempfile::tempdir().expect("temp dir");
    let formats = [
        Format::Ros1(Compression::None),
        Format::Ros1(Compression::Bz2),
        Format::Ros1(Compression::Lz4),
        Format::Mcap(ChunkCompression::None),
        Format::Mcap(ChunkCompression::Zstd),
        Format::Mcap(ChunkCompression::Lz4),
        Format::Db3,
    ];
    let mut summary = Vec::new();
    let mut failures = 0;
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(2);
    for (fi, f) in formats.iter().enumerate() {
        let t0 = Instant::now();
        let clean = make_clean(dir.path(), *f, &bin);
        let bytes = std::fs::read(&clean.file).expect("read clean");
        let tally = Mutex::new(Tally::default());
        let next = AtomicUsize::new(0);
        std::thread::scope(|s| {
            for w in 0..threads {
                let (clean, bytes, tally, next, bin, dir, only, verbose) = (
                    &clean,
                    &bytes,
                    &tally,
                    &next,
                    &bin,
                    dir.path(),
                    &only,
                    verbose,
                );
                s.spawn(move || {
                    // Each worker corrupts its own copy of the input.
                    let work = dir.join(format!("w{fi}_{w}"));
                    let _ = std::fs::remove_dir_all(&work);
                    std::fs::create_dir_all(&work).expect("work dir");
                    let (input, file) = if clean.input == clean.file {
                        let p = work.join(clean.file.file_name().expect("name"));
                        (p.clone(), p)
                    } else {
                        // A bag directory: copy it, corrupt its storage file.
                        let d = work.join("bag");
                        std::fs::create_dir_all(&d).expect("dir");
                        for e in std::fs::read_dir(&clean.input).expect("ls").flatten() {
                            std::fs::copy(e.path(), d.join(e.file_name())).expect("copy");
                        }
                        let p = d.join(clean.file.file_name().expect("name"));
                        (d, p)
                    };
                    let out = work.join("out.csv");
                    loop {
                        let v = next.fetch_add(1, Ordering::Relaxed);
                        if v >= variants {
                            break;
                        }
                        if let Some((fmt, k)) = &only
                            && (*fmt != f.name() || *k != v)
                        {
                            continue;
                        }
                        let mut rng =
                            Rng(seed ^ ((fi as u64) << 48) ^ (v as u64).wrapping_mul(0x9E37));
                        let (bad, what) = mutate(bytes, &clean.regions, &mut rng, v);
                        std::fs::write(&file, &bad).expect("write variant");
                        if only.is_some() {
                            let keep = std::env::temp_dir().join("fuzz_variant");
                            let _ = std::fs::remove_dir_all(&keep);
                            let _ = Command::new("cp").arg("-r").arg(&input).arg(&keep).status();
                            println!("kept {what} as {}", keep.display());
                        }
                        let r = run_child(bin, &input, &out);
                        let outcome = classify(clean, &r, &out);
                        if verbose && !matches!(outcome, Ok(Outcome::Clean)) {
                            let first = r
                                .stderr
                                .lines()
                                .find(|l| l.contains("error") || l.contains("warning"))
                                .unwrap_or("");
                            println!("{} {v} {what}: {outcome:?}: {first}", f.name());
                        }
                        let mut t = tally.lock().expect("tally");
                        let secs = r.elapsed.as_secs_f64();
                        if t.slowest.as_ref().is_none_or(|(s, _, _)| secs > *s) {
                            t.slowest = Some((secs, v, what.clone()));
                        }
                        match outcome {
                            Ok(Outcome::Clean) => t.clean += 1,
                            Ok(Outcome::Altered) => t.altered += 1,
                            Ok(Outcome::Warned) => t.warned += 1,
                            Ok(Outcome::Error) => t.error += 1,
                            Err(e) => {
                                t.failed += 1;
                                println!("FAIL {} variant {v} ({what}): {e}", f.name());
                            }
                        }
                    }
                });
            }
        });
        let t = tally.into_inner().expect("tally");
        failures += t.failed;
        println!(
            "{}: {variants} variants in {:.1} s: {} clean, {} altered values, {} warned, {} errors, {} FAILED; slowest {}",
            f.name(),
            t0.elapsed().as_secs_f64(),
            t.clean,
            t.altered,
            t.warned,
            t.error,
            t.failed,
            t.slowest
                .as_ref()
                .map(|(s, v, w)| format!("{s:.2} s (variant {v}: {w})"))
                .unwrap_or_default()
        );
        summary.push(format!(
            "{} {}/{}/{}/{}/{}",
            f.name(),
            t.clean,
            t.altered,
            t.warned,
            t.error,
            t.failed
        ));
    }
    println!(
        "fuzz campaign (seed {seed:#x}, {variants} variants per format, {:.0} s; clean/altered/warned/error/failed): {}; {} failures",
        start.elapsed().as_secs_f64(),
        summary.join(", "),
        failures
    );
    if failures > 0 {
        std::process::exit(1);
    }
}
