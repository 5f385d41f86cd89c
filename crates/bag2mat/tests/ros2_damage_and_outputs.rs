//! No silent loss in damaged ROS 2 files (sqlite3 pages and row ids, MCAP cut short or with
//! damaged records), exact and bounded loss counts, all-or-none outputs, no abort or hang.
//! The fuzz campaign (`examples/fuzz_campaign.rs`, run by scripts/test.sh) sweeps the same
//! classes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use bag2mat::ChunkCompression;
use bag2mat::test_tools::{
    BtreePage, McapRecord, btree_pages, mcap_chunk_records, mcap_records, reported_losses,
    rowid_fields,
};
use bag2mat::{Ros2BagWriter, Storage};

use crate::common::{run, synthetic};

fn bag2mat() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bag2mat"))
}

/// Imu messages in the defect files (as in the issue: 3,000).
const N: u32 = 3000;

/// A ROS 2 bag directory `dir` with `N` synthetic Imu messages on `imu` and a
/// `std_msgs/String` message on `/status` every 100; returns its storage file.
fn ros2_bag(dir: &Path, storage: Storage) -> PathBuf {
    let mut w =
        Ros2BagWriter::create(&bag2mat::shared::output::Outputs::direct(), dir, storage).unwrap();
    w.set_mcap_chunk_size(8 * 1024);
    let t = w.add_imu_topic("imu").unwrap();
    let s = w
        .add_topic("/status", "std_msgs/msg/String", "string data", "")
        .unwrap();
    for i in 0..N {
        let (rt, imu) = synthetic(i);
        w.write_imu(t, rt.as_nanos(), &imu).unwrap();
        if i % 100 == 0 {
            let text = format!("status {i}\0");
            let mut d = vec![0u8, 1, 0, 0];
            d.extend_from_slice(&(text.len() as u32).to_le_bytes());
            d.extend_from_slice(text.as_bytes());
            w.write_raw(s, rt.as_nanos(), &d).unwrap();
        }
    }
    w.finish().unwrap();
    let name = dir.file_name().unwrap().to_string_lossy().into_owned();
    let ext = if storage == Storage::Sqlite3 {
        "db3"
    } else {
        "mcap"
    };
    dir.join(format!("{name}_0.{ext}"))
}

/// The rows of a CSV bag2mat wrote (header dropped), each as its text.
fn rows_of(csv: &Path) -> Vec<String> {
    std::fs::read_to_string(csv)
        .unwrap_or_default()
        .lines()
        .skip(1)
        .map(str::to_string)
        .collect()
}

/// A damaged input read by the binary: its exit, stderr and rows.
struct Outcome {
    ok: bool,
    stderr: String,
    rows: Vec<String>,
}

fn convert(input: &Path, out: &Path) -> Outcome {
    let _ = std::fs::remove_file(out);
    let (ok, _, stderr) = run(bag2mat()
        .arg(input)
        .arg("imu")
        .arg("-o")
        .arg(out)
        .args(["--format", "csv", "--quiet"]));
    assert!(!stderr.contains("panicked"), "{stderr}");
    Outcome {
        ok,
        stderr,
        rows: rows_of(out),
    }
}

/// Compares a damaged read with the clean rows by value: the clean rows missing from it
/// must all be reported (a count at least as large, never in silence), and no row may be
/// made up or delivered twice.
fn check_by_value(clean: &[String], got: &Outcome, what: &str) -> u64 {
    assert!(got.ok, "{what}: the read failed: {}", got.stderr);
    let mut want: BTreeMap<&str, i64> = BTreeMap::new();
    for r in clean {
        *want.entry(r.as_str()).or_default() += 1;
    }
    for r in &got.rows {
        let n = want.entry(r.as_str()).or_default();
        *n -= 1;
        assert!(*n >= 0, "{what}: row {r} is not a clean row or came twice");
    }
    let missing: u64 = want.values().map(|&n| n.max(0) as u64).sum();
    let rep = reported_losses(&got.stderr, "imu");
    if missing > 0 {
        assert!(
            rep.said && (rep.uncounted || rep.total() >= missing),
            "{what}: {missing} rows lost, reported {rep:?}:\n{}",
            got.stderr
        );
    }
    missing
}

/// The pages of `tree` of kind `kind` in key order.
fn pages_of(pages: &[BtreePage], tree: &str, kind: u8) -> Vec<BtreePage> {
    pages
        .iter()
        .filter(|p| p.tree == tree && p.kind == kind)
        .cloned()
        .collect()
}

/// An edit of a file's bytes.
type ByteEdit<'a> = Box<dyn Fn(&mut Vec<u8>) + 'a>;

/// A bare `.db3` and its clean rows.
fn db3_case(dir: &Path) -> (PathBuf, Vec<String>, Vec<u8>, Vec<BtreePage>) {
    let db = ros2_bag(&dir.join("bag"), Storage::Sqlite3);
    let bare = dir.join("bare.db3");
    std::fs::copy(&db, &bare).unwrap();
    let clean = convert(&bare, &dir.join("clean.csv"));
    assert!(clean.ok && clean.stderr.is_empty(), "{}", clean.stderr);
    assert_eq!(clean.rows.len(), N as usize);
    let bytes = std::fs::read(&bare).unwrap();
    let pages = btree_pages(&bare);
    (bare, clean.rows, bytes, pages)
}

/// 1a: one damaged page of the timestamp index (its last leaf's cell count, its
/// right-most pointer, garbage in its cells) costs no row: the table itself is read.
#[test]
fn db3_damaged_timestamp_index_page_costs_no_row() {
    let dir = tempfile::tempdir().unwrap();
    let (bare, clean, bytes, pages) = db3_case(dir.path());
    let leaves = pages_of(&pages, "timestamp_idx", 0x0A);
    let interior = pages_of(&pages, "timestamp_idx", 0x02);
    assert!(leaves.len() >= 3 && !interior.is_empty(), "{pages:?}");
    let damaged = dir.path().join("d.db3");
    let out = dir.path().join("d.csv");
    let edits: Vec<(&str, ByteEdit)> = vec![
        (
            "the last index leaf's cell count lowered to 1",
            Box::new(|b: &mut Vec<u8>| {
                let p = leaves.last().unwrap();
                b[p.cell_count_at()..p.cell_count_at() + 2].copy_from_slice(&1u16.to_be_bytes());
            }),
        ),
        (
            "an index leaf of the middle filled with 0xFF",
            Box::new(|b: &mut Vec<u8>| {
                let p = &leaves[leaves.len() / 2];
                let a = p.cell_offsets[p.cells as usize / 2];
                b[a..a + 200].fill(0xFF);
            }),
        ),
        (
            "the index root's right-most pointer sent to page 2",
            Box::new(|b: &mut Vec<u8>| {
                let at = interior[0].header + 8;
                b[at..at + 4].copy_from_slice(&2u32.to_be_bytes());
            }),
        ),
    ];
    for (what, edit) in &edits {
        let mut b = bytes.clone();
        edit(&mut b);
        std::fs::write(&damaged, &b).unwrap();
        let got = convert(&damaged, &out);
        assert_eq!(
            check_by_value(&clean, &got, what),
            0,
            "{what}: {}",
            got.stderr
        );
        assert_eq!(got.rows, clean, "{what}: rows differ");
    }
    drop(bare);
}

/// 1b: one damaged row id (the range scan used to stop there, 1,496 of 3,000 rows): the
/// row is read where its id belongs, every row is delivered.
#[test]
fn db3_damaged_row_id_costs_no_row() {
    let dir = tempfile::tempdir().unwrap();
    let (_bare, clean, bytes, pages) = db3_case(dir.path());
    let leaves = pages_of(&pages, "messages", 0x0D);
    let damaged = dir.path().join("d.db3");
    let out = dir.path().join("d.csv");
    for (k, frac) in [(0usize, 2usize), (1, 3), (2, 1)] {
        let page = &leaves[leaves.len() * (frac.min(leaves.len())) / 4];
        let fields = rowid_fields(&bytes, page);
        let (at, len) = fields[(k * 3) % fields.len()];
        let mut b = bytes.clone();
        // Same length, another value: the high bits of the varint's first byte.
        b[at] ^= if len > 1 { 0x40 } else { 0x20 };
        std::fs::write(&damaged, &b).unwrap();
        let got = convert(&damaged, &out);
        let what = format!("row id at byte {at} of page {}", page.number);
        assert_eq!(
            check_by_value(&clean, &got, &what),
            0,
            "{what}: {}",
            got.stderr
        );
    }
}

/// 1c: a page's cell count lowered by 1–3 hides those rows from SQLite: each loss is
/// reported with its exact count and the record times around it, in the middle of the
/// table and at its end (where only the timestamp index still lists them), bare and in
/// the bag directory.
#[test]
fn db3_lowered_cell_count_is_reported_with_count_and_span() {
    let dir = tempfile::tempdir().unwrap();
    let (bare, clean, bytes, pages) = db3_case(dir.path());
    let leaves = pages_of(&pages, "messages", 0x0D);
    let bag = dir.path().join("bag");
    let in_bag = bag.join("bag_0.db3");
    let out = dir.path().join("d.csv");
    for (page, by) in [
        (&leaves[leaves.len() / 3], 1u16),
        (&leaves[leaves.len() / 2], 3),
        (leaves.last().unwrap(), 2),
    ] {
        let mut b = bytes.clone();
        let at = page.cell_count_at();
        b[at..at + 2].copy_from_slice(&(page.cells - by).to_be_bytes());
        for input in [&bare, &bag] {
            let file = if input == &bag { &in_bag } else { &bare };
            std::fs::write(file, &b).unwrap();
            let got = convert(input, &out);
            let what = format!(
                "page {} cell count -{by} ({})",
                page.number,
                input.display()
            );
            let missing = check_by_value(&clean, &got, &what);
            // /status rows are one in 100: the hidden rows are Imu rows here or counted
            // as of unknown topic.
            assert!(missing <= by as u64, "{what}: {missing} lost");
            let rep = reported_losses(&got.stderr, "imu");
            assert!(
                rep.lost + rep.more >= by as u64 - (by as u64 - missing) && rep.lost <= by as u64,
                "{what}: {rep:?}\n{}",
                got.stderr
            );
            assert!(
                got.stderr.contains(&format!("{by} message")) && got.stderr.contains("record time"),
                "{what}: no count or span: {}",
                got.stderr
            );
        }
        std::fs::write(&in_bag, &bytes).unwrap();
    }
}

/// A bare `.mcap` (uncompressed 8 KiB chunks with CRCs, an intact summary) and its clean
/// rows.
fn mcap_case(dir: &Path) -> (PathBuf, Vec<String>, Vec<u8>, Vec<McapRecord>) {
    let file = ros2_bag(&dir.join("mbag"), Storage::Mcap(ChunkCompression::None));
    let bare = dir.join("bare.mcap");
    std::fs::copy(&file, &bare).unwrap();
    let clean = convert(&bare, &dir.join("clean.csv"));
    assert!(clean.ok && clean.stderr.is_empty(), "{}", clean.stderr);
    assert_eq!(clean.rows.len(), N as usize);
    let bytes = std::fs::read(&bare).unwrap();
    let records = mcap_records(&bytes);
    (bare, clean.rows, bytes, records)
}

/// What Foxglove's reader (CRCs checked) recovers of the clean messages on `imu` from each
/// file (tests/py/mcap_recover.py).
fn foxglove_recovers(clean: &Path, files: &[PathBuf]) -> Vec<u64> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/mcap_recover.py");
    let out = bag2mat::test_tools::run_ok(
        Command::new(bag2mat::test_tools::venv_python())
            .arg(script)
            .arg("imu")
            .arg(clean)
            .args(files),
    );
    out.lines().map(|l| l.trim().parse().unwrap()).collect()
}

fn chunks(records: &[McapRecord]) -> Vec<&McapRecord> {
    records.iter().filter(|r| r.op == 0x06).collect()
}

/// 2: an MCAP cut short (no footer, no summary): an unknown opcode, a Data End or Footer
/// opcode in mid-file, a message whose channel id changed — each is counted (or read),
/// never a silent loss of a chunk, a message or the rest of the file.
#[test]
fn mcap_cut_short_opcode_and_channel_damage_is_counted() {
    let dir = tempfile::tempdir().unwrap();
    let (_bare, clean, bytes, records) = mcap_case(dir.path());
    let ch = chunks(&records);
    // Cut inside the chunk at 70 %: no footer, no summary, the tail chunk incomplete.
    let cut_chunk = ch[ch.len() * 7 / 10];
    let cut = &bytes[..cut_chunk.content.start + 100];
    let victim = ch[ch.len() / 3];
    let damaged = dir.path().join("d.mcap");
    let out = dir.path().join("d.csv");
    // What the undamaged cut file gives is the baseline: its tail is gone either way.
    let baseline = |b: &[u8]| {
        std::fs::write(&damaged, b).unwrap();
        let got = convert(&damaged, &out);
        assert!(got.ok && got.rows.len() < clean.len(), "{}", got.stderr);
        got.rows
    };
    let cut_rows = baseline(cut);
    let check = |what: &str, b: &[u8], base: &[String]| {
        std::fs::write(&damaged, b).unwrap();
        let got = convert(&damaged, &out);
        let missing = check_by_value(base, &got, what);
        (got, missing)
    };
    // 2a: an unknown opcode on a chunk.
    let mut b = cut.to_vec();
    b[victim.pos] = 0x42;
    let (got, _) = check("2a unknown opcode", &b, &cut_rows);
    assert!(got.stderr.contains("0x42"), "{}", got.stderr);
    // 2b: a Data End, then a Footer opcode, in mid-file.
    for op in [0x0F, 0x02] {
        let mut b = cut.to_vec();
        b[victim.pos] = op;
        let (got, _) = check(&format!("2b opcode {op:#x} in mid-file"), &b, &cut_rows);
        assert!(
            got.rows.len() > cut_rows.len() / 2,
            "opcode {op:#x}: the rest of the file was dropped: {}",
            got.stderr
        );
    }
    // 2c: a message's channel id changed, in a chunk without CRC (as rosbags writes) whose
    // Message Index records the cut took.
    let last = ch
        .iter()
        .rev()
        .find(|c| c.content.end <= cut.len())
        .unwrap();
    let mut b = bytes[..last.content.end].to_vec();
    let upto_last = baseline(&b);
    let c = last.content.start;
    b[c + 24..c + 28].fill(0);
    let (at, _, content) = mcap_chunk_records(&b, last)
        .into_iter()
        .filter(|r| r.1 == 0x05)
        .nth(3)
        .unwrap();
    let _ = at;
    b[content.start] = 0x77;
    let (got, missing) = check("2c changed channel id", &b, &upto_last);
    assert!(missing >= 1, "{}", got.stderr);
    assert!(got.stderr.contains("channel"), "{}", got.stderr);
}

/// 3: an MCAP with an intact summary: a damaged record length or opcode of a chunk (the
/// first one too) does not abandon the rest of the file — the summary locates every chunk,
/// and bag2mat recovers at least what Foxglove's reader does.
#[test]
fn mcap_damaged_record_header_does_not_abandon_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let (bare, clean, bytes, records) = mcap_case(dir.path());
    let ch = chunks(&records);
    let cases: Vec<(&str, ByteEdit)> = vec![
        (
            "a middle chunk's length set huge",
            Box::new(|b: &mut Vec<u8>| {
                let p = ch[ch.len() / 2].pos;
                b[p + 1..p + 9].copy_from_slice(&u64::MAX.to_le_bytes());
            }),
        ),
        (
            "a middle chunk's length off by 5",
            Box::new(|b: &mut Vec<u8>| {
                let p = ch[ch.len() / 2].pos;
                let l = u64::from_le_bytes(b[p + 1..p + 9].try_into().unwrap());
                b[p + 1..p + 9].copy_from_slice(&(l + 5).to_le_bytes());
            }),
        ),
        (
            "the first chunk's opcode changed",
            Box::new(|b: &mut Vec<u8>| b[ch[0].pos] = 0x2A),
        ),
        (
            "the first chunk's length zeroed",
            Box::new(|b: &mut Vec<u8>| {
                let p = ch[0].pos;
                b[p + 1..p + 9].fill(0);
            }),
        ),
    ];
    let mut files = Vec::new();
    let mut ours = Vec::new();
    for (k, (what, edit)) in cases.iter().enumerate() {
        let mut b = bytes.clone();
        edit(&mut b);
        let p = dir.path().join(format!("d{k}.mcap"));
        std::fs::write(&p, &b).unwrap();
        let got = convert(&p, &dir.path().join(format!("d{k}.csv")));
        let missing = check_by_value(&clean, &got, what);
        assert!(
            missing <= 40,
            "{what}: {missing} rows lost where the summary locates every chunk: {}",
            got.stderr
        );
        ours.push(got.rows.len() as u64);
        files.push(p);
    }
    let theirs = foxglove_recovers(&bare, &files);
    for ((what, _), (o, t)) in cases.iter().zip(ours.iter().zip(&theirs)) {
        assert!(
            o >= t,
            "{what}: Foxglove's reader recovers {t}, bag2mat {o}"
        );
    }
}

/// 4: loss counts are exact, with time spans (a chunk that fails its CRC counts what its
/// message index lists), and counts a damaged index states are bounded by what the file
/// can hold (a message index count of 0x08000000, a metadata.yaml count of i64::MAX).
#[test]
fn loss_counts_are_exact_and_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let (_bare, clean, bytes, records) = mcap_case(dir.path());
    let ch = chunks(&records);
    let damaged = dir.path().join("d.mcap");
    let out = dir.path().join("d.csv");
    // A chunk body damaged in a file cut short: its message index counts what it held.
    let victim = ch[ch.len() / 4];
    let keep = ch[ch.len() / 2].pos;
    let mut b = bytes[..keep + 20].to_vec();
    std::fs::write(&damaged, &b).unwrap();
    let cut_rows = convert(&damaged, &out).rows;
    b[victim.content.start + 200] ^= 0xFF;
    std::fs::write(&damaged, &b).unwrap();
    let got = convert(&damaged, &out);
    let missing = check_by_value(&cut_rows, &got, "chunk CRC");
    let in_victim = mcap_chunk_records(&bytes, victim)
        .iter()
        .filter(|r| {
            r.1 == 0x05 && u16::from_le_bytes([bytes[r.2.start], bytes[r.2.start + 1]]) == 1
        })
        .count() as u64;
    assert!(
        got.stderr
            .contains(&format!("{in_victim} messages lost (record time")),
        "the chunk's {in_victim} messages are not counted with their span: {}",
        got.stderr
    );
    assert!(missing >= in_victim);
    // A message index count of 0x08000000 where every row is delivered: no loss is claimed.
    let mi = records
        .iter()
        .find(|r| r.op == 0x07 && r.pos > ch[ch.len() / 2].pos)
        .unwrap();
    let mut b = bytes.clone();
    b[mi.content.start + 2..mi.content.start + 6].copy_from_slice(&0x0800_0000u32.to_le_bytes());
    std::fs::write(&damaged, &b).unwrap();
    let got = convert(&damaged, &out);
    assert_eq!(check_by_value(&clean, &got, "index count"), 0);
    let rep = reported_losses(&got.stderr, "imu");
    assert!(rep.lost + rep.more < N as u64, "{rep:?}: {}", got.stderr);
    // metadata.yaml promising i64::MAX messages: bounded, no impossible count.
    let bag = dir.path().join("mbag");
    let meta = std::fs::read_to_string(bag.join("metadata.yaml")).unwrap();
    let edited = meta.replacen(
        &format!("message_count: {N}"),
        "message_count: 9223372036854775807",
        2,
    );
    assert_ne!(edited, meta);
    std::fs::write(bag.join("metadata.yaml"), edited).unwrap();
    let got = convert(&bag, &out);
    assert_eq!(check_by_value(&clean, &got, "metadata count"), 0);
    assert!(
        !got.stderr
            .lines()
            .any(|l| l.contains("922337203685477") && l.contains("lost")),
        "an impossible count: {}",
        got.stderr
    );
    assert!(
        got.stderr.contains("the count is damaged"),
        "{}",
        got.stderr
    );
    let rep = reported_losses(&got.stderr, "imu");
    assert!(rep.lost < N as u64, "{rep:?}: {}", got.stderr);
}

/// 8: a symlink loop given as the output is refused (an error, nothing written, the links
/// left as they are), not turned into a regular file.
#[test]
fn a_symlink_loop_as_output_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let db = ros2_bag(&dir.path().join("bag"), Storage::Sqlite3);
    let (a, b) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    std::os::unix::fs::symlink(&b, &a).unwrap();
    std::os::unix::fs::symlink(&a, &b).unwrap();
    let (ok, _, err) = run(bag2mat().arg(&db).arg("imu").arg("-o").arg(&a).arg("-q"));
    assert!(!ok, "{err}");
    assert!(
        err.starts_with("bag2mat: error:") && err.contains("loop of symbolic links"),
        "{err}"
    );
    for l in [&a, &b] {
        assert!(
            std::fs::symlink_metadata(l)
                .unwrap()
                .file_type()
                .is_symlink()
        );
    }
    assert!(bag2mat::test_tools::temp_files_in(dir.path()).is_empty());
}

/// 9: a damaged metadata.yaml is said in one line (no doubled "error:", no excerpt of the
/// file), and the storage files beside it are still read.
#[test]
fn a_damaged_metadata_yaml_is_one_plain_line() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("bag");
    ros2_bag(&bag, Storage::Sqlite3);
    let clean = convert(&bag, &dir.path().join("clean.csv"));
    let meta = bag.join("metadata.yaml");
    let text = std::fs::read_to_string(&meta).unwrap();
    std::fs::write(
        &meta,
        text.replacen("message_count: ", "message_count: [", 1),
    )
    .unwrap();
    let got = convert(&bag, &dir.path().join("d.csv"));
    assert!(got.ok, "{}", got.stderr);
    assert_eq!(got.rows, clean.rows);
    let lines: Vec<&str> = got.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{}", got.stderr);
    assert!(
        lines[0].starts_with("warning: ")
            && lines[0].contains("metadata.yaml is damaged")
            && !lines[0].contains("error:"),
        "{}",
        got.stderr
    );
}
