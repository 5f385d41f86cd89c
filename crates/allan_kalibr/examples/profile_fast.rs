//! Phase timings of the fast path on a .mat (development aid for the benchmark).
//! `cargo run --release -p allan_kalibr --example profile_fast -- FILE.mat RATE`
//! (a long input: `sim bag --duration 14400 -o x.bag`, then `bag2mat x.bag -o x.mat`)
use std::time::Instant;

use allan_kalibr::{TauGrid, prefix_in_place, sig2_prefix_fused, sig2_tiled};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    let d = bag2mat::read_data_imu(std::path::Path::new(&a[1]))?;
    let rate: f64 = a[2].parse()?;
    let [_, mut x, mut y, ..] = d.columns;
    let t = Instant::now();
    let g = TauGrid::new(x.len(), rate)?;
    let ms = g.distinct_m();
    eprintln!(
        "grid {:.4} s ({} distinct m)",
        t.elapsed().as_secs_f64(),
        ms.len()
    );
    let t = Instant::now();
    prefix_in_place(&mut x);
    eprintln!("prefix {:.4} s", t.elapsed().as_secs_f64());
    let t = Instant::now();
    let v = sig2_tiled(&mut x, &ms);
    eprintln!("tiled {:.4} s ({})", t.elapsed().as_secs_f64(), v[0]);
    let t = Instant::now();
    let v = sig2_prefix_fused(&mut y, &ms);
    eprintln!(
        "fused prefix+tiled {:.4} s ({})",
        t.elapsed().as_secs_f64(),
        v[0]
    );
    Ok(())
}
