//! Reads every Imu topic of an input through bag2mat's one read path (as the analysers do)
//! and prints the rows per topic and the seconds the read took: what `scripts/bench.sh`
//! times against pandas and pyulog. `read_log INPUT`.

/// The binaries' allocator, so that the read is timed as the tools run it.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom =
    bag2mat::shared::alloc::ExitOnOom::new("read_log");

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .ok_or_else(|| anyhow::anyhow!("usage: read_log INPUT"))?;
    let t = std::time::Instant::now();
    let sel = bag2mat::TopicSelector {
        topics: vec![],
        all_imu: true,
        preferred: None,
    };
    let r = bag2mat::read_imu_topics(
        std::path::Path::new(&path),
        &sel,
        &bag2mat::ReadOptions { quiet: true },
    )?;
    let s = t.elapsed().as_secs_f64();
    for x in &r.series {
        println!("{} {}", x.topic, x.len());
    }
    println!("seconds {s:.3}");
    Ok(())
}
