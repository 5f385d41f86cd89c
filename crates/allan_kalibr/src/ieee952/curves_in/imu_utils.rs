//! The imu_utils data directory of [`super`]: `data_<name>_{gyr,acc}_{t,x,y,z}.txt`, one
//! number per line; overlapping, gyro in imu_utils' pseudo-deg/h, acc m/s². Its sample
//! count, when not given, is the one its grid implies.

use std::path::{Path, PathBuf};

use super::super::oadev::Overlap;
use super::{
    Curves, CurvesError, Format, IMU_UTILS_PSEUDO_DEG_H, ImuUtilsRaw, Options, dedup_rows, given_n,
    io, sensor_curves,
};
use bag2mat::Sensor;

/// `data_<name>_gyr_t.txt` → name.
pub(super) fn imu_utils_name(fname: &str) -> Option<String> {
    let rest = fname.strip_prefix("data_")?;
    for suf in [
        "_gyr_t.txt",
        "_gyr_x.txt",
        "_gyr_y.txt",
        "_gyr_z.txt",
        "_acc_t.txt",
        "_acc_x.txt",
        "_acc_y.txt",
        "_acc_z.txt",
    ] {
        if let Some(n) = rest.strip_suffix(suf) {
            // not the fitted curves data_<name>_sim_*
            return (!n.ends_with("_sim")).then(|| n.to_string());
        }
    }
    None
}

fn numbers_file(path: &Path) -> Result<Vec<f64>, CurvesError> {
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            let t = l.trim();
            // imu_utils writes NaN as "-nan" (glibc)
            if t.eq_ignore_ascii_case("-nan") || t.eq_ignore_ascii_case("nan") {
                return Ok(f64::NAN);
            }
            t.parse::<f64>().map_err(|_| CurvesError::Parse {
                path: path.to_path_buf(),
                line: i + 1,
                what: format!("not a number: {t:?}"),
            })
        })
        .collect()
}

/// Reads imu_utils' curves of IMU `name` (the only one in `dir` when not given).
pub(super) fn read_imu_utils(
    dir: &Path,
    name: Option<&str>,
    opts: &Options,
) -> Result<Curves, CurvesError> {
    let name = match name {
        Some(n) => n.to_string(),
        None => only_imu_utils_name(dir)?,
    };
    let raw = read_imu_utils_files(dir, name)?;
    let (gyr_t, gyr, acc_t, acc) = (&raw.gyr_t, &raw.gyr, &raw.acc_t, &raw.acc);
    // imu_utils: τ = period·factor, the first factor is 1
    let tau0 = gyr_t[0];
    let ms: Vec<usize> = gyr_t.iter().map(|t| (t / tau0).round() as usize).collect();
    let rate = 1.0 / tau0;
    let mut notes = Vec::new();
    let n = imu_utils_n(opts, tau0, rate, &ms, &raw, &mut notes);
    let rows_g: Vec<[f64; 3]> = (0..ms.len())
        .map(|i| [gyr[0][i], gyr[1][i], gyr[2][i]])
        .collect();
    let (mg, cg) = dedup_rows(ms.clone(), rows_g);
    let ms_a: Vec<usize> = acc_t.iter().map(|t| (t / tau0).round() as usize).collect();
    let rows_a: Vec<[f64; 3]> = (0..ms_a.len())
        .map(|i| [acc[0][i], acc[1][i], acc[2][i]])
        .collect();
    let (ma, ca) = dedup_rows(ms_a, rows_a);
    Ok(Curves {
        format: Format::ImuUtils,
        sensors: vec![
            sensor_curves(
                Sensor::Gyro,
                &mg,
                tau0,
                n,
                Overlap::Overlapping,
                &cg,
                1.0 / IMU_UTILS_PSEUDO_DEG_H,
            ),
            sensor_curves(Sensor::Acc, &ma, tau0, n, Overlap::Overlapping, &ca, 1.0),
        ],
        rate,
        notes,
        imu_utils: Some(raw),
    })
}

/// The one IMU name of the imu_utils files in `dir` (no name given): an error when there
/// are none, or curves of several IMUs to choose from.
fn only_imu_utils_name(dir: &Path) -> Result<String, CurvesError> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map_err(io(dir))?
        .filter_map(|e| e.ok())
        .filter_map(|e| imu_utils_name(&e.file_name().to_string_lossy()))
        .collect();
    names.sort();
    names.dedup();
    match names.len() {
        0 => Err(CurvesError::UnknownFormat {
            path: dir.to_path_buf(),
            why: "a directory without data_<name>_{gyr,acc}_t.txt files".into(),
        }),
        1 => Ok(names.remove(0)),
        _ => Err(CurvesError::Options(format!(
            "{}: curves of several IMUs ({}); choose one with --name",
            dir.display(),
            names.join(", ")
        ))),
    }
}

/// imu_utils' file of sensor `s` (`gyr`, `acc`) and column `ax` (`t`, `x`, `y`, `z`).
fn imu_utils_file(dir: &Path, name: &str, s: &str, ax: &str) -> PathBuf {
    dir.join(format!("data_{name}_{s}_{ax}.txt"))
}

/// Reads imu_utils' eight files of IMU `name` and checks them: each sensor's τ starts
/// positive and every column has one value per τ.
fn read_imu_utils_files(dir: &Path, name: String) -> Result<ImuUtilsRaw, CurvesError> {
    let f = |s: &str, ax: &str| imu_utils_file(dir, &name, s, ax);
    let gyr_t = numbers_file(&f("gyr", "t"))?;
    let acc_t = numbers_file(&f("acc", "t"))?;
    let gyr: [Vec<f64>; 3] = [
        numbers_file(&f("gyr", "x"))?,
        numbers_file(&f("gyr", "y"))?,
        numbers_file(&f("gyr", "z"))?,
    ];
    let acc: [Vec<f64>; 3] = [
        numbers_file(&f("acc", "x"))?,
        numbers_file(&f("acc", "y"))?,
        numbers_file(&f("acc", "z"))?,
    ];
    for (t, cols, s) in [(&gyr_t, &gyr, "gyr"), (&acc_t, &acc, "acc")] {
        if t.first()
            .is_none_or(|v| !super::super::fit::is_positive(*v))
        {
            return Err(CurvesError::Parse {
                path: f(s, "t"),
                line: 1,
                what: "no positive first τ".into(),
            });
        }
        for (c, ax) in cols.iter().zip(["x", "y", "z"]) {
            if c.len() != t.len() {
                return Err(CurvesError::Parse {
                    path: f(s, ax),
                    line: c.len() + 1,
                    what: format!("{} values for {} τ", c.len(), t.len()),
                });
            }
        }
    }
    Ok(ImuUtilsRaw {
        name,
        gyr_t,
        gyr,
        acc_t,
        acc,
    })
}

/// The sample count of imu_utils' curves (grid factors `ms` of `tau0`): the one the options
/// give, or else the one the grid implies; the note saying which goes to `notes`.
fn imu_utils_n(
    opts: &Options,
    tau0: f64,
    rate: f64,
    ms: &[usize],
    raw: &ImuUtilsRaw,
    notes: &mut Vec<String>,
) -> Option<usize> {
    let (gyr, acc) = (&raw.gyr, &raw.acc);
    match given_n(opts, tau0, rate) {
        Some((n, why)) => {
            notes.push(format!("{why}: N = {n}"));
            Some(n)
        }
        None => {
            // the last factor is the largest power of two ≤ N/2, or one more (quirk); a point
            // with a value needs N − 2m ≥ 1 (docs/upstream/imu_utils.md §3.4), so the last factor with one
            // bounds N from below too (issue 18.10: 2·maxStride alone is below it when the
            // grid ends at maxStride + 1)
            let last = *ms.last().unwrap_or(&1);
            let max_stride = if last.is_power_of_two() {
                last
            } else {
                (last - 1).next_power_of_two()
            };
            let valued = |i: usize| {
                gyr.iter()
                    .chain(acc.iter())
                    .any(|c| c.get(i).is_some_and(|v| v.is_finite() && *v > 0.0))
            };
            let last_valued = (0..ms.len())
                .rev()
                .find(|&i| valued(i))
                .map_or(1, |i| ms[i]);
            let n = (2 * max_stride).max(2 * last_valued + 1);
            notes.push(format!(
                "sample count not given: imu_utils' grid (last factor {last}, the last with a value {last_valued}) implies {n} ≤ N < {}; \
                 using N = {n} (intervals slightly wide). Give --duration or --samples for exact intervals.",
                4 * max_stride
            ));
            Some(n)
        }
    }
}
