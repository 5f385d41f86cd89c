//! Writes the synthetic logs the cross-checks and `scripts/bench.sh` read:
//! `write_logs ulog OUT SECONDS RATE` (PX4 IMU topics, bag2mat::test_tools::ulog_imu_log),
//! `write_logs ulog-fifo OUT SECONDS RATE` (PX4's raw FIFO topics, 6 samples a message),
//! `write_logs dataflash OUT SECONDS RATE` (IMU and ISBH/ISBD, formats::dataflash::write),
//! `write_logs euroc DIR SECONDS RATE` (DIR/mav0/imu0/data.csv, EuRoC/ASL header).

use std::io::BufWriter;

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    anyhow::ensure!(
        a.len() == 5,
        "usage: write_logs ulog|ulog-fifo|dataflash|euroc OUT SECONDS RATE"
    );
    let (out, seconds, rate) = (std::path::Path::new(&a[2]), a[3].parse()?, a[4].parse()?);
    match a[1].as_str() {
        "ulog" => {
            let spec = bag2mat::test_tools::UlogImuSpec {
                seconds,
                rate,
                instances: 2,
                dropout_ms: Some(40),
                seed: 20,
            };
            bag2mat::test_tools::ulog_imu_log(BufWriter::new(std::fs::File::create(out)?), &spec)?;
        }
        "ulog-fifo" => {
            bag2mat::test_tools::ulog_fifo_log(
                BufWriter::new(std::fs::File::create(out)?),
                seconds,
                rate,
                6,
                20,
            )?;
        }
        "dataflash" => {
            bag2mat::test_tools::dataflash_imu_log(
                BufWriter::new(std::fs::File::create(out)?),
                seconds,
                rate,
                20,
            )?;
        }
        "euroc" => {
            let dir = out.join("mav0/imu0");
            std::fs::create_dir_all(&dir)?;
            euroc(&dir.join("data.csv"), seconds, rate)?;
        }
        other => anyhow::bail!("unknown log kind {other}"),
    }
    Ok(())
}

/// A EuRoC/ASL `data.csv` of white noise: ns stamps, rad/s, m/s², 17 decimals.
fn euroc(path: &std::path::Path, seconds: f64, rate: f64) -> anyhow::Result<()> {
    use std::io::Write;
    let mut w = BufWriter::with_capacity(1 << 20, std::fs::File::create(path)?);
    writeln!(
        w,
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"
    )?;
    let mut st = 20u64;
    let mut next = || bag2mat::test_tools::synthetic_noise(&mut st);
    let n = (seconds * rate) as u64;
    let dt = (1e9 / rate).round() as u64;
    for i in 0..n {
        let v: [f64; 6] = std::array::from_fn(|k| {
            (if k == 5 { 9.81 } else { 0.0 }) + if k < 3 { 1e-3 } else { 2e-2 } * next()
        });
        writeln!(
            w,
            "{},{:.17},{:.17},{:.17},{:.17},{:.17},{:.17}",
            1_403_636_579_758_555_392 + i * dt,
            v[0],
            v[1],
            v[2],
            v[3],
            v[4],
            v[5]
        )?;
    }
    w.flush()?;
    Ok(())
}
