//! Damaged ROS 1 bags lose nothing in silence (flipped chunk info, damaged message headers,
//! resynchronising, bad index bytes, counts that never size memory), outputs never clobber
//! (devices and links, the input, temporary files, the format from the extension), and the
//! messages follow one convention. The fuzz campaign that sweeps the same failure classes
//! over every format is `examples/fuzz_campaign.rs` (run by scripts/test.sh).

use std::path::Path;
use std::process::Command;

use bag2mat::test_tools::{BagOp, BagRecordHeader, raw_bag_record, read_u32};
use bag2mat::{Compression, NoSuchPart, PartError, ReadOptions, Ros1ChunkError, read_imu_series};

use crate::common::{run, synthetic, write_synthetic};

fn bag2mat() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bag2mat"))
}

/// Messages in the defect bags: about six 768 KiB chunks of ~2,100 messages, as in the issue.
const N: u32 = 12_000;

/// An edit of a bag's bytes.
type ByteEdit<'a> = Box<dyn Fn(&mut Vec<u8>) + 'a>;

/// A top-level record of a ROS 1 bag: where it starts, its op, and its header and data ranges.
#[derive(Debug, Clone)]
pub(crate) struct Rec {
    pub(crate) pos: usize,
    pub(crate) op: BagOp,
    pub(crate) header: std::ops::Range<usize>,
    pub(crate) data: std::ops::Range<usize>,
}

/// The top-level records of a well-formed bag, in file order.
pub(crate) fn records(bytes: &[u8]) -> Vec<Rec> {
    let mut pos = 13;
    let mut out = Vec::new();
    while let Some(r) = raw_bag_record(bytes, pos) {
        let hstart = pos + 4;
        let h = BagRecordHeader::parse(r.header).unwrap();
        let dstart = hstart + r.header.len() + 4;
        out.push(Rec {
            pos,
            op: h.op().unwrap(),
            header: hstart..hstart + r.header.len(),
            data: dstart..dstart + r.data.len(),
        });
        pos = r.end;
    }
    out
}

/// Offset of field `name`'s value inside the record header `range`.
pub(crate) fn field(bytes: &[u8], range: &std::ops::Range<usize>, name: &str) -> usize {
    let mut pos = range.start;
    while pos < range.end {
        let len = read_u32(bytes, pos).unwrap() as usize;
        let f = &bytes[pos + 4..pos + 4 + len];
        if f.starts_with(name.as_bytes()) && f[name.len()] == b'=' {
            return pos + 4 + name.len() + 1;
        }
        pos += 4 + len;
    }
    panic!("no field {name}");
}

/// The rows a clean read of the synthetic stream gives: (seq, record time ns).
fn clean_rows(n: u32) -> Vec<(u32, u64)> {
    (0..n)
        .map(|i| {
            let (t, imu) = synthetic(i);
            (imu.seq, t.as_nanos())
        })
        .collect()
}

/// Either every row, or fewer with a note that names the loss (never duplicates, never
/// fewer in silence).
fn check_complete_or_reported(path: &Path, what: &str) {
    let s = match read_imu_series(path, "imu", &ReadOptions { quiet: true }) {
        Ok(s) => s,
        Err(e) => panic!("{what}: the bag became unreadable: {e}"),
    };
    let got: Vec<(u32, u64)> = s
        .seq
        .iter()
        .zip(&s.record_time)
        .map(|(q, t)| (*q, t.as_nanos()))
        .collect();
    let want = clean_rows(N);
    if got == want {
        return;
    }
    let mut uniq = got.clone();
    uniq.dedup();
    assert_eq!(uniq.len(), got.len(), "{what}: duplicated rows");
    assert!(
        got.iter().all(|r| want.binary_search(r).is_ok()),
        "{what}: rows that are not in the bag"
    );
    let missing = want.len() - got.len();
    assert!(
        s.notes
            .iter()
            .any(|n| n.text.contains(&format!("{missing} ")) && n.text.contains("lost")),
        "{what}: {missing} rows missing, notes {:?}",
        s.notes
    );
}

#[test]
fn flipped_chunk_info_is_reported_or_read() {
    let dir = tempfile::tempdir().unwrap();
    for c in [Compression::None, Compression::Lz4] {
        let path = dir.path().join(format!("d1_{}.bag", c.name()));
        write_synthetic(&path, "imu", N, c, false);
        let good = std::fs::read(&path).unwrap();
        let recs = records(&good);
        let infos: Vec<&Rec> = recs.iter().filter(|r| r.op == BagOp::ChunkInfo).collect();
        let chunks: Vec<&Rec> = recs.iter().filter(|r| r.op == BagOp::Chunk).collect();
        assert!(infos.len() >= 5, "{} chunk infos", infos.len());
        let info = infos[1];
        let edits: Vec<(&str, ByteEdit)> = vec![
            (
                "connection id 0 -> 7",
                Box::new(|b: &mut Vec<u8>| b[info.data.start] ^= 7),
            ),
            (
                "count -> 0",
                Box::new(|b: &mut Vec<u8>| b[info.data.start + 4..info.data.start + 8].fill(0)),
            ),
            (
                "chunk_pos -> the first chunk",
                Box::new(|b: &mut Vec<u8>| {
                    let at = field(b, &info.header, "chunk_pos");
                    b[at..at + 8].copy_from_slice(&(chunks[0].pos as u64).to_le_bytes());
                }),
            ),
            (
                "chunk_pos -> inside a chunk",
                Box::new(|b: &mut Vec<u8>| {
                    let at = field(b, &info.header, "chunk_pos");
                    b[at..at + 8].copy_from_slice(&(chunks[2].pos as u64 + 777).to_le_bytes());
                }),
            ),
            (
                "chunk_pos bit flip",
                Box::new(|b: &mut Vec<u8>| {
                    let at = field(b, &info.header, "chunk_pos");
                    b[at + 1] ^= 0x10;
                }),
            ),
        ];
        for (what, edit) in edits {
            let mut bad = good.clone();
            edit(&mut bad);
            std::fs::write(&path, &bad).unwrap();
            check_complete_or_reported(&path, &format!("{c:?}, chunk info {what}"));
        }
    }
}

/// Damages the record header of message `k` (0-based) of `bytes` (an uncompressed bag).
fn message_header(bytes: &[u8], k: usize) -> std::ops::Range<usize> {
    let recs = records(bytes);
    let mut seen = 0;
    for ch in recs.iter().filter(|r| r.op == BagOp::Chunk) {
        let mut pos = ch.data.start;
        while pos < ch.data.end {
            let r = raw_bag_record(bytes, pos).unwrap();
            let h = BagRecordHeader::parse(r.header).unwrap();
            if h.op().unwrap() == BagOp::MessageData {
                if seen == k {
                    return pos + 4..pos + 4 + r.header.len();
                }
                seen += 1;
            }
            pos = r.end;
        }
    }
    panic!("no message {k}");
}

#[test]
fn damaged_message_header_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("d2.bag");
    write_synthetic(&path, "imu", N, Compression::None, false);
    let good = std::fs::read(&path).unwrap();
    type Edit = Box<dyn Fn(&mut Vec<u8>, &std::ops::Range<usize>)>;
    let edits: Vec<(&str, Edit)> = vec![
        (
            "op 0x02 -> 0x09",
            Box::new(|b, h| {
                let at = field(b, h, "op");
                b[at] = 0x09;
            }),
        ),
        (
            "field name conn -> coNn",
            Box::new(|b, h| {
                let at = field(b, h, "conn");
                b[at - 3] = b'N';
            }),
        ),
        (
            "conn 0 -> 5",
            Box::new(|b, h| {
                let at = field(b, h, "conn");
                b[at] = 5;
            }),
        ),
    ];
    let h = message_header(&good, 3000);
    for (what, edit) in &edits {
        let mut bad = good.clone();
        edit(&mut bad, &h);
        std::fs::write(&path, &bad).unwrap();
        let s = read_imu_series(&path, "imu", &ReadOptions { quiet: true }).unwrap();
        assert_eq!(s.len(), N as usize - 1, "{what}");
        let (t, _) = synthetic(3000);
        assert!(
            s.notes.iter().any(|n| n.text.contains("1 message")
                && n.text.contains("lost")
                && n.text.contains(&t.to_string())),
            "{what}: the lost message is not named (count, time): {:?}",
            s.notes
        );
    }
    // A 1-message bag whose message is damaged: an error, not "0 messages".
    let one = dir.path().join("one.bag");
    write_synthetic(&one, "imu", 1, Compression::None, false);
    let good = std::fs::read(&one).unwrap();
    let h = message_header(&good, 0);
    for (what, edit) in &edits {
        let mut bad = good.clone();
        edit(&mut bad, &h);
        std::fs::write(&one, &bad).unwrap();
        let out = dir.path().join("one.mat");
        let (ok, _, err) = run(bag2mat().arg(&one).arg("imu").arg("-o").arg(&out));
        assert!(!ok, "{what}: exit 0 with a lost message; stderr {err}");
        assert!(err.contains("1 message"), "{what}: {err}");
        assert!(!out.exists(), "{what}: wrote an empty file");
    }
}

#[test]
fn all_lost_is_an_error_and_recovery_resynchronises() {
    let dir = tempfile::tempdir().unwrap();
    // Every message of the topic lost: an error, no 0x7 file.
    let path = dir.path().join("d3.bag");
    write_synthetic(&path, "imu", 3, Compression::None, false);
    let good = std::fs::read(&path).unwrap();
    let mut bad = good.clone();
    for k in 0..3 {
        let h = message_header(&good, k);
        let at = field(&good, &h, "op");
        bad[at] = 0x09;
    }
    std::fs::write(&path, &bad).unwrap();
    let out = dir.path().join("d3.mat");
    let (ok, _, err) = run(bag2mat().arg(&path).arg("imu").arg("-o").arg(&out));
    assert!(!ok, "all messages lost, exit 0: {err}");
    assert!(err.contains("bag2mat: error:"), "{err}");
    assert!(!out.exists());

    // One bad framing byte inside an uncompressed chunk loses that record, not the rest of
    // the chunk: the reader resynchronises on the next valid record.
    write_synthetic(&path, "imu", N, Compression::None, false);
    let good = std::fs::read(&path).unwrap();
    let h = message_header(&good, 3000);
    let mut bad = good.clone();
    // The record's header length (the 4 bytes before its header).
    bad[h.start - 2] = 0x7f;
    std::fs::write(&path, &bad).unwrap();
    let s = read_imu_series(&path, "imu", &ReadOptions { quiet: true }).unwrap();
    assert!(
        s.len() >= N as usize - 1,
        "{} rows: the rest of the chunk was dropped; notes {:?}",
        s.len(),
        s.notes
    );
    check_complete_or_reported(&path, "bad framing byte");
}

#[test]
fn bad_index_byte_still_reads_every_chunk() {
    let dir = tempfile::tempdir().unwrap();
    for c in [Compression::None, Compression::Bz2] {
        let path = dir.path().join(format!("d4_{}.bag", c.name()));
        write_synthetic(&path, "imu", N, c, false);
        let good = std::fs::read(&path).unwrap();
        let recs = records(&good);
        let first_index = recs
            .iter()
            .position(|r| r.op == BagOp::ChunkInfo)
            .map(|i| {
                // The index section starts with the connection records before the infos.
                let mut j = i;
                while j > 0 && recs[j - 1].op == BagOp::Connection {
                    j -= 1;
                }
                j
            })
            .unwrap();
        let index = &recs[first_index..];
        let targets = [
            ("index connection header length", index[0].pos + 1),
            ("index connection op", field(&good, &index[0].header, "op")),
            (
                "chunk info header length",
                index.iter().find(|r| r.op == BagOp::ChunkInfo).unwrap().pos + 2,
            ),
            ("last chunk info data", index.last().unwrap().data.start + 1),
        ];
        for (what, at) in targets {
            let mut bad = good.clone();
            bad[at] ^= 0x5a;
            std::fs::write(&path, &bad).unwrap();
            let s = read_imu_series(&path, "imu", &ReadOptions { quiet: true })
                .unwrap_or_else(|e| panic!("{c:?}, {what}: {e}"));
            assert_eq!(s.len(), N as usize, "{c:?}, {what}: {:?}", s.notes);
        }
        // The same bag with its index cut off reads every row too.
        std::fs::write(&path, &good[..index[0].pos]).unwrap();
        let s = read_imu_series(&path, "imu", &ReadOptions { quiet: true }).unwrap();
        assert_eq!(s.len(), N as usize, "{c:?}, index cut off");
    }
}

/// Runs `cmd` (a shell command line) under an address-space limit of `mb` MiB.
fn limited(mb: u64, cmd: &str) -> (bool, String, String) {
    run(Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {}; exec {cmd}", mb * 1024)))
}

#[test]
fn counts_never_size_memory() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("d5.bag");
    write_synthetic(&path, "imu", N, Compression::None, false);
    let good = std::fs::read(&path).unwrap();
    let recs = records(&good);
    let info = recs
        .iter()
        .find(|r| r.op == BagOp::ChunkInfo)
        .unwrap()
        .clone();
    // 12,000 rows are 1 MB of matrix; the limit leaves room for threads and buffers only.
    const LIMIT_MIB: u64 = 600;
    for count in [0xFFFF_FFFFu32, 0x0800_0000] {
        let mut bad = good.clone();
        bad[info.data.start + 4..info.data.start + 8].copy_from_slice(&count.to_le_bytes());
        std::fs::write(&path, &bad).unwrap();
        let out = dir.path().join("d5.mat");
        let (ok, _, err) = limited(
            LIMIT_MIB,
            &format!(
                "{} {} imu -o {} --quiet",
                env!("CARGO_BIN_EXE_bag2mat"),
                path.display(),
                out.display()
            ),
        );
        assert!(ok, "count {count:#x}: {err}");
        assert_eq!(
            bag2mat::read_data_imu(&out).unwrap().rows(),
            N as usize,
            "count {count:#x}"
        );
    }
}

/// A small bag and the matrix bag2mat writes from it (for the output tests).
fn small_bag(dir: &Path) -> (std::path::PathBuf, Vec<u8>) {
    let bag = dir.join("small.bag");
    write_synthetic(&bag, "imu", 300, Compression::None, false);
    let out = dir.join("ref.mat");
    let (ok, _, err) = run(bag2mat().arg(&bag).arg("imu").arg("-o").arg(&out).arg("-q"));
    assert!(ok, "{err}");
    (bag, std::fs::read(&out).unwrap())
}

#[test]
fn outputs_write_through_devices_and_links() {
    let dir = tempfile::tempdir().unwrap();
    let (bag, want) = small_bag(dir.path());
    // A FIFO (what /dev/null and /dev/stdout are to a rename: not regular files, which a
    // rename as root would replace) is written through and stays a FIFO; also behind a
    // symlink, as /dev/stdout is. The test never touches the real /dev entries.
    let fifo = dir.path().join("pipe");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo on a fresh path in our temporary directory.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let stdout_like = dir.path().join("stdout");
    std::os::unix::fs::symlink(&fifo, &stdout_like).unwrap();
    for o in [&fifo, &stdout_like] {
        let (tx, rx) = std::sync::mpsc::channel();
        {
            let fifo = fifo.clone();
            std::thread::spawn(move || tx.send(std::fs::read(&fifo).unwrap()));
        }
        let (ok, _, err) = run(bag2mat()
            .arg(&bag)
            .arg("imu")
            .arg("-o")
            .arg(o)
            .args(["--format", "mat", "-q"]));
        let got = rx.recv_timeout(std::time::Duration::from_secs(5));
        if got.is_err() {
            // Nothing came through the FIFO: release the reader before failing.
            let _ = std::fs::OpenOptions::new().write(true).open(&fifo);
        }
        assert!(ok, "{err}");
        assert_eq!(
            got.ok(),
            Some(want.clone()),
            "-o {}: the FIFO got nothing",
            o.display()
        );
        let m = std::fs::metadata(&fifo).unwrap();
        assert!(!m.is_file(), "the FIFO became a regular file");
    }
    // "-" writes the matrix to standard output.
    let out = bag2mat()
        .arg(&bag)
        .arg("imu")
        .args(["-o", "-", "--format", "mat", "-q"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(out.stdout, want, "-o -: stdout is not the matrix");
    // A symlink is followed: its target gets the matrix, the link stays a link.
    let real = dir.path().join("real.mat");
    std::fs::write(&real, b"old").unwrap();
    let link = dir.path().join("link.mat");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let (ok, _, err) = run(bag2mat()
        .arg(&bag)
        .arg("imu")
        .arg("-o")
        .arg(&link)
        .arg("-q"));
    assert!(ok, "{err}");
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink(),
        "the link was replaced"
    );
    assert_eq!(std::fs::read(&real).unwrap(), want);
}

/// `bag2mat … -o - | head`: a reader that stops early is not an error (no "Broken pipe"
/// message, exit 0), as for every Unix filter.
#[test]
fn stdout_closed_by_the_reader_is_not_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("big.bag");
    // 20 000 rows of csv (~2 MB): far more than a pipe buffer holds.
    write_synthetic(&bag, "imu", 20_000, Compression::None, false);
    let mut child = bag2mat()
        .arg(&bag)
        .arg("imu")
        .args(["-o", "-", "--format", "csv", "-q"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Read one line, then close the pipe.
    let mut first = [0u8; 16];
    std::io::Read::read_exact(child.stdout.as_mut().unwrap(), &mut first).unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "exit {:?}: {err}", out.status);
    assert!(!err.contains("error"), "{err}");
}

#[test]
fn the_input_is_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let (bag, _) = small_bag(dir.path());
    // A bag named .mat: the default output is the input itself.
    let named_mat = dir.path().join("rec.mat");
    std::fs::copy(&bag, &named_mat).unwrap();
    let before = std::fs::read(&named_mat).unwrap();
    let (ok, _, err) = run(bag2mat().arg(&named_mat).arg("imu"));
    assert!(!ok, "overwrote its input");
    assert!(
        err.contains("bag2mat: error:") && err.contains("input"),
        "{err}"
    );
    assert_eq!(std::fs::read(&named_mat).unwrap(), before);
    // -o equal to the input, also through another name (a hard link).
    let alias = dir.path().join("alias.bag");
    std::fs::hard_link(&bag, &alias).unwrap();
    let before = std::fs::read(&bag).unwrap();
    for o in [&bag, &alias] {
        let (ok, _, err) = run(bag2mat()
            .arg(&bag)
            .arg("imu")
            .arg("-o")
            .arg(o)
            .args(["--format", "mat"]));
        assert!(!ok, "-o {}: overwrote its input", o.display());
        assert!(err.contains("input"), "{err}");
        assert_eq!(std::fs::read(&bag).unwrap(), before);
    }
}

use bag2mat::test_tools::temp_files_in as temps;

#[test]
fn failed_outputs_leave_no_temp_files() {
    let dir = tempfile::tempdir().unwrap();
    let (bag, _) = small_bag(dir.path());
    // The output name is a directory.
    let d = dir.path().join("out.mat");
    std::fs::create_dir(&d).unwrap();
    let (ok, _, err) = run(bag2mat().arg(&bag).arg("imu").arg("-o").arg(&d));
    assert!(!ok);
    assert!(
        err.contains("directory") && !err.contains("os error"),
        "{err}"
    );
    assert_eq!(temps(dir.path()), Vec::<String>::new());
    // The final rename fails (a directory is in the way of one of two topics' files): no
    // temp file, and (all or none) no file of the other topic either.
    let two = dir.path().join("two.bag");
    {
        let mut w = bag2mat::BagWriter::create(
            &bag2mat::shared::output::Outputs::direct(),
            &two,
            Compression::None,
        )
        .unwrap();
        let a = w.add_imu_connection("/imu0");
        let b = w.add_imu_connection("/imu1");
        for i in 0..100 {
            let (t, m) = synthetic(i);
            w.write_imu(a, t, &m).unwrap();
            w.write_imu(b, t, &m).unwrap();
        }
        w.finish().unwrap();
    }
    let out = dir.path().join("outs");
    std::fs::create_dir_all(out.join("imu1/two.mat/x")).unwrap();
    let (ok, _, err) = run(bag2mat()
        .arg(&two)
        .arg("--all-imu-topics")
        .arg("-o")
        .arg(&out));
    assert!(!ok, "{err}");
    assert!(
        !out.join("imu0/two.mat").exists(),
        "half of the outputs written"
    );
    for sub in ["imu0", "imu1"] {
        assert_eq!(temps(&out.join(sub)), Vec::<String>::new(), "{sub}");
    }
}

#[test]
fn format_follows_the_extension() {
    let dir = tempfile::tempdir().unwrap();
    let (bag, _) = small_bag(dir.path());
    let csv = dir.path().join("x.csv");
    let (ok, _, err) = run(bag2mat().arg(&bag).arg("imu").arg("-o").arg(&csv).arg("-q"));
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("t,ax,ay,az,wx,wy,wz\n"), "not CSV");
    assert_eq!(text.lines().count(), 301);
    let npy = dir.path().join("x.npy");
    let (ok, _, _) = run(bag2mat().arg(&bag).arg("imu").arg("-o").arg(&npy).arg("-q"));
    assert!(ok);
    assert!(std::fs::read(&npy).unwrap().starts_with(b"\x93NUMPY"));
    // A contradiction is a usage error (exit 2), and nothing is written.
    let bad = dir.path().join("y.csv");
    let out = bag2mat()
        .arg(&bag)
        .arg("imu")
        .arg("-o")
        .arg(&bad)
        .args(["--format", "npy"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .starts_with("bag2mat: error: --format npy contradicts")
    );
    assert!(!bad.exists());
}

/// Exit code, stderr.
fn status(cmd: &mut Command) -> (Option<i32>, String) {
    let out = cmd.output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn one_error_convention() {
    let dir = tempfile::tempdir().unwrap();
    // Failures: exit 1, one line "bag2mat: error: <what>: <cause>", no OS error numbers.
    let missing = dir.path().join("missing.bag");
    for args in [
        vec![missing.display().to_string(), "imu".into()],
        // no topic: the input's only Imu topic, so reading it is what fails
        vec![missing.display().to_string()],
        vec!["info".into(), missing.display().to_string()],
    ] {
        let (code, err) = status(bag2mat().args(&args));
        assert_eq!(code, Some(1), "{args:?}: {err}");
        let errors: Vec<&str> = err.lines().filter(|l| l.contains("error")).collect();
        assert_eq!(errors.len(), 1, "{args:?}: {err}");
        assert!(
            errors[0].starts_with(&format!(
                "bag2mat: error: {}: no such file",
                missing.display()
            )),
            "{args:?}: {err}"
        );
        assert!(!err.contains("os error"), "{err}");
    }
    // Usage errors: exit 2, same prefix.
    for args in [
        vec![],
        vec!["--no-such-flag".to_string()],
        vec!["x.bag".into(), "--format".into(), "xls".into()],
    ] {
        let (code, err) = status(bag2mat().args(&args));
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(err.starts_with("bag2mat: error: "), "{args:?}: {err}");
        assert_eq!(err.matches("error:").count(), 1, "{args:?}: {err}");
    }
}

#[test]
fn imu_plus_another_type_on_one_topic_converts_the_imu() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("mixed.bag");
    {
        let mut w = bag2mat::BagWriter::create(
            &bag2mat::shared::output::Outputs::direct(),
            &bag,
            Compression::None,
        )
        .unwrap();
        let imu = w.add_imu_connection("imu");
        let other = bag2mat::test_tools::add_string_connection(&mut w, "imu");
        for i in 0..500 {
            let (t, m) = synthetic(i);
            w.write_imu(imu, t, &m).unwrap();
            if i % 50 == 0 {
                w.write_raw(other, t, &bag2mat::test_tools::string_message("hi"))
                    .unwrap();
            }
        }
        w.finish().unwrap();
    }
    let out = dir.path().join("mixed.csv");
    let (ok, _, err) = run(bag2mat().arg(&bag).arg("imu").arg("-o").arg(&out));
    assert!(ok, "a mixed topic was rejected: {err}");
    assert!(
        err.contains("warning: topic 'imu' also carries std_msgs/String (10 messages)"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&out).unwrap().lines().count(), 501);
}

#[test]
fn messages_a_person_can_act_on() {
    let dir = tempfile::tempdir().unwrap();
    // Control bytes in a topic name from the file are escaped.
    let bag = dir.path().join("esc.bag");
    write_synthetic(&bag, "/i\x1b[2Jmu", 10, Compression::None, false);
    let (ok, _, err) = run(bag2mat().arg(&bag).arg("imu"));
    assert!(!ok);
    assert!(!err.contains('\x1b'), "raw control byte printed: {err:?}");
    assert!(err.contains("/i\\u{1b}[2Jmu"), "{err}");
    // A bag cut short before any complete chunk says so.
    write_synthetic(&bag, "imu", 3000, Compression::None, false);
    let full = std::fs::read(&bag).unwrap();
    let cut = dir.path().join("cut.bag");
    std::fs::write(&cut, &full[..4117 + 40]).unwrap();
    let (ok, _, err) = run(bag2mat().arg(&cut).arg("imu"));
    assert!(!ok);
    assert!(
        err.contains("truncated") && !err.contains("no topics at all"),
        "{err}"
    );
    // A file in the way of the output: named as the user named it, no OS error number, no
    // temporary path.
    let (ok, _, err) = run(bag2mat()
        .arg(&bag)
        .arg("imu")
        .arg("-o")
        .arg(dir.path().join("esc.bag/x.mat")));
    assert!(!ok);
    assert!(
        err.contains("esc.bag/x.mat: a component of the path is not a directory")
            && !err.contains("os error")
            && !err.contains(".x.mat."),
        "{err}"
    );
}

/// The kind each part of the bag at `p` stops with (`None`: read to its end), keyed by the
/// part's label; and the kind a part index past the last says.
fn part_errors(p: &Path) -> (Vec<(String, Option<PartError>)>, Option<PartError>) {
    let src = bag2mat::open_input(p).unwrap();
    let each = (0..src.parts().len())
        .map(|k| {
            let r = src.read_part(k, &|_| true, &mut |_, _, _| {});
            (src.parts()[k].label.clone(), r.error)
        })
        .collect();
    let past = src.read_part(src.parts().len(), &|_| true, &mut |_, _, _| {});
    (each, past.error)
}

/// A chunk whose bz2 block does not decompress stops its part as a decompression error of
/// that codec, and one whose stated size is not its body's as a size error carrying both
/// sizes: told by the error's kind (no reading of its words); every other chunk reads whole.
#[test]
fn a_damaged_chunk_stops_its_part_with_the_kind_of_its_damage() {
    let dir = tempfile::tempdir().unwrap();
    for (compression, name) in [(Compression::Bz2, "bz2"), (Compression::None, "plain")] {
        let p = dir.path().join(format!("{name}.bag"));
        write_synthetic(&p, "/imu", N, compression, false);
        let mut bytes = std::fs::read(&p).unwrap();
        let chunks: Vec<Rec> = records(&bytes)
            .into_iter()
            .filter(|r| r.op == BagOp::Chunk)
            .collect();
        assert!(chunks.len() >= 3, "{name}: {} chunks", chunks.len());
        let hit = chunks[1].clone();
        let stated = hit.data.len();
        match compression {
            // bz2's stream header is 4 bytes ("BZh9"); the block magic after it is zeroed
            Compression::Bz2 => bytes[hit.data.start + 4..hit.data.start + 64].fill(0),
            // the chunk header's uncompressed size, one more than the body holds
            _ => {
                let at = field(&bytes, &hit.header, "size");
                let size = read_u32(&bytes, at).unwrap();
                assert_eq!(
                    size as usize, stated,
                    "{name}: an uncompressed chunk's size"
                );
                bytes[at..at + 4].copy_from_slice(&(size + 1).to_le_bytes());
            }
        }
        std::fs::write(&p, &bytes).unwrap();
        let (each, past) = part_errors(&p);
        let label = format!("chunk at byte {}", hit.pos);
        assert!(each.iter().any(|(l, _)| *l == label), "{name}: {each:?}");
        for (l, e) in &each {
            if *l != label {
                assert!(e.is_none(), "{name}, {l}: {e:?}");
                continue;
            }
            match compression {
                Compression::Bz2 => assert!(
                    matches!(
                        e,
                        Some(PartError::Ros1Chunk(Ros1ChunkError::Decompress {
                            codec: "bz2",
                            ..
                        }))
                    ),
                    "{name}, {l}: {e:?}"
                ),
                _ => assert!(
                    matches!(
                        e,
                        Some(PartError::Ros1Chunk(Ros1ChunkError::Size { got, size }))
                            if *got == stated && *size == stated + 1
                    ),
                    "{name}, {l}: {e:?}"
                ),
            }
        }
        assert!(
            matches!(
                past,
                Some(PartError::NoSuchPart {
                    wording: NoSuchPart::Chunk,
                    ..
                })
            ),
            "{name}: {past:?}"
        );
    }
}
