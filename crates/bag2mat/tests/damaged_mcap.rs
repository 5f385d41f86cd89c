//! A damaged MCAP chunk record loses nothing in silence and claims no loss that did not
//! happen (issue 45): a chunk whose opcode is damaged into a message index's or a message's
//! is read as the chunk, in a file cut short (no summary) and in a file with its summary.

use std::path::{Path, PathBuf};
use std::process::Command;

use bag2mat::test_tools::{mcap_records, reported_losses};
use bag2mat::{ChunkCompression, Ros2BagWriter, Storage};

use crate::common::{run, synthetic};

/// Imu messages in the files (as in the issue: 3,000).
const N: u32 = 3000;

/// An MCAP file (zstd chunks of 8 kB) with `N` Imu messages on `imu`.
fn mcap(dir: &Path) -> PathBuf {
    let d = dir.join("bag");
    let mut w = Ros2BagWriter::create(
        &bag2mat::shared::output::Outputs::direct(),
        &d,
        Storage::Mcap(ChunkCompression::Zstd),
    )
    .unwrap();
    w.set_mcap_chunk_size(8 * 1024);
    let t = w.add_imu_topic("imu").unwrap();
    for i in 0..N {
        let (rt, imu) = synthetic(i);
        w.write_imu(t, rt.as_nanos(), &imu).unwrap();
    }
    w.finish().unwrap();
    d.join("bag_0.mcap")
}

/// The rows and stderr of converting `imu` of `bytes`.
fn convert(dir: &Path, name: &str, bytes: &[u8]) -> (Vec<String>, String) {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    let out = dir.join(format!("{name}.csv"));
    let (ok, _, err) = run(Command::new(env!("CARGO_BIN_EXE_bag2mat"))
        .arg(&p)
        .args(["imu", "-q", "--format", "csv", "-o"])
        .arg(&out));
    assert!(ok, "{name}: {err}");
    let rows = std::fs::read_to_string(&out)
        .unwrap()
        .lines()
        .skip(1)
        .map(str::to_string)
        .collect();
    (rows, err)
}

/// A chunk's opcode changed to a message index's (0x07) or a message's (0x05): its rows are
/// read, and the warnings count what they counted without the damage.
#[test]
fn mcap_a_chunk_whose_opcode_is_damaged_is_read_as_the_chunk() {
    let dir = tempfile::tempdir().unwrap();
    let whole = std::fs::read(mcap(dir.path())).unwrap();
    let chunks: Vec<usize> = mcap_records(&whole)
        .iter()
        .filter(|r| r.op == 0x06)
        .map(|r| r.pos)
        .collect();
    // cut short inside the chunk at 70 %: no footer, no summary (a killed recorder)
    let cut = &whole[..chunks[chunks.len() * 7 / 10] + 100];
    for (what, file) in [("cut short", cut), ("with its summary", &whole[..])] {
        let (rows0, err0) = convert(dir.path(), "clean.mcap", file);
        for op in [0x07u8, 0x05] {
            for k in [1usize, chunks.len() / 3] {
                let mut b = file.to_vec();
                b[chunks[k]] = op;
                let (rows, err) = convert(dir.path(), "op.mcap", &b);
                assert_eq!(rows, rows0, "{what}: chunk {k} as opcode {op:#x}: {err}");
                assert_eq!(
                    reported_losses(&err, "imu"),
                    reported_losses(&err0, "imu"),
                    "{what}: chunk {k} as opcode {op:#x}: {err}"
                );
            }
        }
    }
}
