//! A damaged MCAP chunk record loses nothing in silence and claims no loss that did not
//! happen (issue 45): a chunk whose opcode is damaged into a message index's or a message's
//! is read as the chunk, in a file cut short (no summary) and in a file with its summary.

use std::path::{Path, PathBuf};
use std::process::Command;

use bag2mat::test_tools::{mcap_records, reported_losses};
use bag2mat::{ChunkCompression, McapChunkError, NoSuchPart, PartError, Ros2BagWriter, Storage};

use crate::common::{run, synthetic};

/// Imu messages in the files (as in the issue: 3,000).
const N: u32 = 3000;

/// An MCAP file (zstd chunks of 8 kB) with `N` Imu messages on `imu`.
fn mcap(dir: &Path) -> PathBuf {
    mcap_with(dir, ChunkCompression::Zstd)
}

/// An MCAP file (chunks of 8 kB, compressed as said) with `N` Imu messages on `imu`.
fn mcap_with(dir: &Path, compression: ChunkCompression) -> PathBuf {
    let d = dir.join("bag");
    let mut w = Ros2BagWriter::create(
        &bag2mat::shared::output::Outputs::direct(),
        &d,
        Storage::Mcap(compression),
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

/// A chunk whose stored records no longer match their CRC (uncompressed) or no longer
/// decompress (zstd) stops its part with that kind, the CRC error carrying the CRC the chunk
/// stores; told by the error's kind (no reading of its words). Every other chunk reads whole.
#[test]
fn mcap_a_damaged_chunk_stops_its_part_with_the_kind_of_its_damage() {
    for compression in [ChunkCompression::None, ChunkCompression::Zstd] {
        let dir = tempfile::tempdir().unwrap();
        let p = mcap_with(dir.path(), compression);
        let mut b = std::fs::read(&p).unwrap();
        let chunks: Vec<_> = mcap_records(&b)
            .into_iter()
            .filter(|r| r.op == 0x06)
            .collect();
        assert!(
            chunks.len() >= 3,
            "{compression:?}: {} chunks",
            chunks.len()
        );
        let hit = &chunks[1];
        let c = hit.content.start;
        // the chunk's fields: start and end time, uncompressed size, CRC, compression name,
        // then its records' length and the records
        let stored = u32::from_le_bytes(b[c + 24..c + 28].try_into().unwrap());
        assert_ne!(stored, 0, "{compression:?}: the writer stores a CRC");
        let name_len = u32::from_le_bytes(b[c + 28..c + 32].try_into().unwrap()) as usize;
        let records = c + 32 + name_len + 8;
        let (label, at) = (format!("chunk at byte {}", hit.pos), hit.content.end - 16);
        assert!(at > records + 64, "{compression:?}: a chunk of records");
        match compression {
            // a byte of the last message's data
            ChunkCompression::None => b[at] ^= 0xFF,
            // the zstd frame's magic number
            _ => {
                assert_eq!(b[records..records + 4], [0x28, 0xB5, 0x2F, 0xFD]);
                b[records..records + 4].fill(0);
            }
        }
        let damaged = dir.path().join("damaged.mcap");
        std::fs::write(&damaged, &b).unwrap();
        let src = bag2mat::open_input(&damaged).unwrap();
        let parts = src.parts().len();
        let mut seen = false;
        for k in 0..parts {
            let e = src.read_part(k, &|_| true, &mut |_, _, _| {}).error;
            let l = &src.parts()[k].label;
            if *l != label {
                assert!(e.is_none(), "{compression:?}, {l}: {e:?}");
                continue;
            }
            seen = true;
            let kind_ok = match compression {
                ChunkCompression::None => matches!(
                    &e,
                    Some(PartError::McapChunk(McapChunkError::Crc { got, stored: s }))
                        if *s == stored && *got != stored
                ),
                _ => matches!(&e, Some(PartError::McapChunk(McapChunkError::Zstd(_)))),
            };
            assert!(kind_ok, "{compression:?}, {l}: {e:?}");
        }
        assert!(seen, "{compression:?}: no part {label}");
        let past = src.read_part(parts, &|_| true, &mut |_, _, _| {}).error;
        assert!(
            matches!(
                past,
                Some(PartError::NoSuchPart {
                    wording: NoSuchPart::Part,
                    ..
                })
            ),
            "{compression:?}: {past:?}"
        );
    }
}
