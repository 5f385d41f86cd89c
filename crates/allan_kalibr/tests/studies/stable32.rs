//! Parity with Stable32 1.53 on two real clock data sets (testdata/external, see its README):
//! overlapping and normal ADEV equal at Stable32's printed 5 significant digits at every listed
//! τ, and where our noise identification gives Stable32's α, the 68.3 % bounds within 1 %.

use allan_kalibr::{
    CurveData, IdMethod, Ieee952Config, Overlap, Phase, analyse_ieee952, chi2_interval,
    greenhall_edf, identify,
};
use std::io::Read;

/// Issue 6: bounds within 1 % of Stable32's where the identified α agrees.
const BOUND_REL_TOL: f64 = 0.01;
/// Stable32's Min/Max Sigma are at confidence factor 0.683 (file headers).
const STABLE32_CONFIDENCE: f64 = 0.683;

struct Row {
    m: usize,
    count: usize,
    alpha: i32,
    lo: f64,
    sigma: f64,
    hi: f64,
}

fn read_text(name: &str) -> String {
    let file = bag2mat::test_tools::testdata().join("external").join(name);
    let path = file.display();
    let bytes = std::fs::read(&file).unwrap_or_else(|e| panic!("{path}: {e}"));
    if name.ends_with(".gz") {
        let mut s = String::new();
        flate2::read::GzDecoder::new(&bytes[..])
            .read_to_string(&mut s)
            .unwrap_or_else(|e| panic!("{path}: {e}"));
        s
    } else {
        String::from_utf8(bytes).unwrap_or_else(|e| panic!("{path}: {e}"))
    }
}

fn numbers(name: &str) -> Vec<f64> {
    read_text(name)
        .lines()
        .filter(|l| !l.trim_start().starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            l.trim()
                .parse::<f64>()
                .unwrap_or_else(|e| panic!("{name}: {l:?}: {e}"))
        })
        .collect()
}

fn table(name: &str) -> Vec<Row> {
    read_text(name)
        .lines()
        .filter(|l| !l.trim_start().starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            let p = |i: usize| {
                f[i].parse::<f64>()
                    .unwrap_or_else(|e| panic!("{name}: {l:?}: {e}"))
            };
            Row {
                m: p(0) as usize,
                count: p(2) as usize,
                alpha: p(3) as i32,
                lo: p(4),
                sigma: p(5),
                hi: p(6),
            }
        })
        .collect()
}

/// GPS 1PPS phase (s) → rate y[k] = (x[k+1] − x[k])/τ0, τ0 = 1 s.
fn gps_rate() -> Vec<f64> {
    let x = numbers("gps_1pps_phase_data.txt.gz");
    assert_eq!(x.len(), 241_218, "GPS phase point count");
    x.windows(2).map(|w| w[1] - w[0]).collect()
}

/// OCXO frequency (Hz) → fractional frequency y = f/1e7 − 1, computed as (f − 1e7)/1e7 (the
/// subtraction is exact, so no digits are lost to the offset).
fn ocxo_rate() -> Vec<f64> {
    let f = numbers("ocxo_frequency.txt");
    assert_eq!(f.len(), 19_982, "OCXO point count");
    f.iter().map(|v| (v - 1e7) / 1e7).collect()
}

fn five_digits(v: f64) -> String {
    format!("{v:.4e}")
}

/// Every listed τ: our deviation printed at 5 significant digits equals Stable32's.
fn check_sigma(label: &str, phase: &Phase, rows: &[Row], kind: Overlap) {
    assert!(!rows.is_empty(), "{label}: empty reference table");
    let mut worst = 0.0f64;
    for (i, r) in rows.iter().enumerate() {
        let p = phase
            .avar(r.m, kind)
            .unwrap_or_else(|| panic!("{label} row {i} m={}: no value", r.m));
        let dev = p.avar.sqrt();
        assert_eq!(p.n_terms, r.count, "{label} row {i} m={}: term count", r.m);
        assert_eq!(
            five_digits(dev),
            five_digits(r.sigma),
            "{label} row {i} m={}: expected {:.4e}, got {dev:.6e} (tolerance: equal at 5 significant digits)",
            r.m,
            r.sigma
        );
        worst = worst.max((dev / r.sigma - 1.0).abs());
    }
    println!(
        "{label}: {} τ values equal at 5 significant digits (max |rel diff| to the printed value {worst:.2e})",
        rows.len()
    );
}

/// Bounds where α agrees; returns (compared, total, max bound deviation, max half-width deviation).
fn check_bounds(
    label: &str,
    phase: &Phase,
    rows: &[Row],
    kind: Overlap,
) -> (usize, usize, f64, f64) {
    let n_phase = phase.n_rate() + 1;
    let (mut compared, mut worst, mut worst_hw) = (0, 0.0f64, 0.0f64);
    println!("{label}: m, alpha Stable32/ours (method), lo dev %, hi dev %, half-width dev %");
    for (i, r) in rows.iter().enumerate() {
        let id = identify(phase, r.m);
        let dev = phase.avar(r.m, kind).unwrap().avar.sqrt();
        if id.alpha != Some(r.alpha) {
            println!(
                "  {:>6} {:>2}/{:?} ({:?}) not compared",
                r.m, r.alpha, id.alpha, id.method
            );
            continue;
        }
        let nu = greenhall_edf(r.alpha, r.m, n_phase, kind).unwrap();
        let (lo, hi) = chi2_interval(dev, nu, STABLE32_CONFIDENCE).unwrap();
        let dl = lo / r.lo - 1.0;
        let dh = hi / r.hi - 1.0;
        let dhw_lo = (dev - lo) / (r.sigma - r.lo) - 1.0;
        let dhw_hi = (hi - dev) / (r.hi - r.sigma) - 1.0;
        println!(
            "  {:>6} {:>2}/{:>2} ({:?}) edf {nu:>10.1} lo {:+.4}% hi {:+.4}% half-width {:+.2}%/{:+.2}%",
            r.m,
            r.alpha,
            r.alpha,
            id.method,
            100.0 * dl,
            100.0 * dh,
            100.0 * dhw_lo,
            100.0 * dhw_hi
        );
        for (what, d, want, got) in [("Min Sigma", dl, r.lo, lo), ("Max Sigma", dh, r.hi, hi)] {
            assert!(
                d.abs() < BOUND_REL_TOL,
                "{label} row {i} m={} alpha={} {what}: expected {want:e}, got {got:e}, tol {BOUND_REL_TOL}",
                r.m,
                r.alpha
            );
        }
        compared += 1;
        worst = worst.max(dl.abs()).max(dh.abs());
        worst_hw = worst_hw.max(dhw_lo.abs()).max(dhw_hi.abs());
    }
    println!(
        "{label}: bounds compared at {compared}/{} τ, max bound deviation {:.4} %, max half-width deviation {:.2} %",
        rows.len(),
        100.0 * worst,
        100.0 * worst_hw
    );
    (compared, rows.len(), worst, worst_hw)
}

#[test]
fn stable32_gps_oadev_octave() {
    let phase = Phase::from_rate(&gps_rate(), 1.0);
    let rows = table("stable32_OADEV_octave.txt");
    check_sigma("GPS OADEV octave", &phase, &rows, Overlap::Overlapping);
    let (compared, total, _, _) =
        check_bounds("GPS OADEV octave", &phase, &rows, Overlap::Overlapping);
    // lag-1 ID applies at 13 of the 16 octave τ (N/m ≥ 30); it must agree at all of them
    assert!(
        compared >= 13,
        "GPS OADEV: α agreed at only {compared}/{total} τ"
    );
}

#[test]
fn stable32_gps_adev_decade() {
    let phase = Phase::from_rate(&gps_rate(), 1.0);
    let rows = table("stable32_ADEV_decade.txt");
    check_sigma("GPS ADEV decade", &phase, &rows, Overlap::Normal);
    let (compared, total, _, _) = check_bounds("GPS ADEV decade", &phase, &rows, Overlap::Normal);
    assert!(
        compared >= 10,
        "GPS ADEV: α agreed at only {compared}/{total} τ"
    );
}

#[test]
fn stable32_ocxo_oadev_alltau() {
    let phase = Phase::from_rate(&ocxo_rate(), 1.0);
    check_sigma(
        "OCXO OADEV all-tau",
        &phase,
        &table("stable32_oadev_alltau.txt"),
        Overlap::Overlapping,
    );
}

#[test]
fn stable32_ocxo_adev_alltau() {
    let phase = Phase::from_rate(&ocxo_rate(), 1.0);
    check_sigma(
        "OCXO ADEV all-tau",
        &phase,
        &table("stable32_adev_alltau.txt"),
        Overlap::Normal,
    );
}

#[test]
fn ocxo_alpha_agreement_is_reported() {
    // The all-τ files carry Stable32's α but no bounds: report how often our ID agrees.
    let phase = Phase::from_rate(&ocxo_rate(), 1.0);
    let rows = table("stable32_oadev_alltau.txt");
    let mut agree = 0;
    let mut lag1 = 0;
    for r in &rows {
        let id = identify(&phase, r.m);
        if id.method == IdMethod::Lag1 {
            lag1 += 1;
            agree += (id.alpha == Some(r.alpha)) as usize;
        }
    }
    println!(
        "OCXO OADEV all-tau: α equal to Stable32's at {agree}/{lag1} lag-1 τ ({} rows)",
        rows.len()
    );
    // the noise there is a mixture (α flips between neighbours in Stable32's own column), so
    // only demand a clear majority
    assert!(agree * 10 >= lag1 * 7, "α agreement {agree}/{lag1}");
}

#[test]
fn analyse_runs_on_clock_data() {
    // Not IMU data (flicker PM / white PM dominate): the full pipeline must still give a finite
    // curve with bounds around every point, and a fit whose misfit shows in χ²/dof.
    let a = analyse_ieee952(&gps_rate(), 1.0, &Ieee952Config::default()).expect("GPS rate series");
    assert!(!a.curve.is_empty());
    for (i, p) in a.curve.iter().enumerate() {
        assert!(
            p.lo < p.adev && p.adev < p.hi,
            "point {i} m={}: {} not inside [{}, {}]",
            p.m,
            p.adev,
            p.lo,
            p.hi
        );
    }
    let f = a.fit.as_ref().expect("fit");
    println!(
        "GPS: {} points, fit χ²/dof {:.1}, terms {:?}",
        a.curve.len(),
        f.chi2_per_dof,
        a.terms.as_array().map(|t| t.verdict)
    );
}

/// Issue 17.3: the section's curve against allantools' `oadev` (the Python package the
/// field checks itself against; pinned in `scripts/test.sh`, run from its virtual
/// environment — missing, the test fails) at every cluster size of the section's grid, on
/// both clock files. The two sum the same squares in another order.
const ALLANTOOLS_REL_TOL: f64 = 1e-9;

/// allantools' `oadev` of `data` (`"freq"` or `"phase"`, τ0 = 1 s) at the cluster sizes `ms`:
/// (m, deviation, number of terms) as the package returns them.
fn allantools_oadev(data: &[f64], data_type: &str, ms: &[usize]) -> Vec<(usize, f64, usize)> {
    use std::io::Write as _;
    let dir = tempfile::tempdir().expect("temp dir");
    let input = dir.path().join("data.txt");
    let mut f = std::fs::File::create(&input).expect("data file");
    for v in data {
        writeln!(f, "{v:e}").expect("write");
    }
    drop(f);
    let taus: Vec<String> = ms.iter().map(|m| m.to_string()).collect();
    let script = format!(
        "import sys, numpy, allantools\n\
         d = numpy.loadtxt(sys.argv[1])\n\
         t, dev, err, n = allantools.oadev(d, rate=1.0, data_type='{data_type}', taus=numpy.array([{}], dtype=float))\n\
         for a, b, c in zip(t, dev, n): print('%d %.17g %d' % (round(a), b, c))\n",
        taus.join(",")
    );
    let out = bag2mat::test_tools::run_ok(
        std::process::Command::new(bag2mat::test_tools::venv_python())
            .arg("-c")
            .arg(script)
            .arg(&input),
    );
    out.lines()
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (
                f[0].parse().expect("tau"),
                f[1].parse().expect("dev"),
                f[2].parse().expect("n"),
            )
        })
        .collect()
}

fn check_against_allantools(label: &str, rate: &[f64], data: &[f64], data_type: &str) {
    let curve = CurveData::from_samples(rate, 1.0, &Ieee952Config::default())
        .unwrap_or_else(|e| panic!("{label}: {e}"));
    let ms: Vec<usize> = curve.points.iter().map(|p| p.m).collect();
    let theirs = allantools_oadev(data, data_type, &ms);
    assert_eq!(
        theirs.iter().map(|t| t.0).collect::<Vec<_>>(),
        ms,
        "{label}: allantools returned other cluster sizes"
    );
    let mut worst = 0.0f64;
    for (p, &(m, dev, n)) in curve.points.iter().zip(&theirs) {
        let ours = p.avar.sqrt();
        let rel = (ours / dev - 1.0).abs();
        assert_eq!(n, rate.len() + 1 - 2 * m, "{label} m={m}: term count");
        assert!(
            rel < ALLANTOOLS_REL_TOL,
            "{label} m={m}: ours {ours:e}, allantools {dev:e}, tol {ALLANTOOLS_REL_TOL:e}"
        );
        worst = worst.max(rel);
    }
    println!(
        "{label}: the curve equals allantools' oadev at all {} cluster sizes ({} above m = 256), max |rel diff| {worst:.1e}",
        ms.len(),
        ms.iter().filter(|&&m| m > 256).count()
    );
}

#[test]
fn the_curve_equals_allantools_oadev() {
    let ocxo = ocxo_rate();
    check_against_allantools("OCXO (frequency)", &ocxo, &ocxo, "freq");
    let gps_phase = numbers("gps_1pps_phase_data.txt.gz");
    check_against_allantools("GPS 1PPS (phase)", &gps_rate(), &gps_phase, "phase");
}
