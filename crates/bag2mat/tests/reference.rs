//! Parity with the real kalibr_allan `bagconvert` on the reference bags: the N×7 matrix must
//! be the same to the bit (sha256 of the row-major little-endian f64 matrix, as recorded in
//! `kalibr/bagconvert_mat.json`), for bz2 (p1, p4), lz4 (p2, two topics) and none (p3).

use sha2::{Digest, Sha256};

use crate::common::{CASES, case_bag, testdata};
use bag2mat::bag_to_data_imu;

/// The first quoted string after `"key":`.
fn first_quoted_after<'a>(json: &'a str, key: &str) -> &'a str {
    let rest = &json[json.find(&format!("\"{key}\":")).unwrap() + key.len() + 3..];
    let start = rest.find('"').unwrap() + 1;
    &rest[start..start + rest[start..].find('"').unwrap()]
}

fn json_field<'a>(json: &'a str, key: &str) -> &'a str {
    let at = json
        .find(&format!("\"{key}\""))
        .unwrap_or_else(|| panic!("no {key} in json"));
    let rest = &json[at + key.len() + 2..];
    let start = rest.find('"').unwrap() + 1;
    let end = start + rest[start..].find('"').unwrap();
    &rest[start..end]
}

#[test]
fn matrix_equals_bagconvert_bit_for_bit() {
    for (case, topic) in CASES {
        let json =
            std::fs::read_to_string(testdata().join(case).join("kalibr/bagconvert_mat.json"))
                .unwrap();
        let conv = bag_to_data_imu(&case_bag(case), topic, true).unwrap();
        let d = &conv.data;
        let mut h = Sha256::new();
        for i in 0..d.rows() {
            for v in d.row(i) {
                h.update(v.to_le_bytes());
            }
        }
        let got = format!("{:x}", h.finalize());
        assert_eq!(
            got,
            json_field(&json, "sha256_rowmajor_f64le"),
            "case {case}: sha256 of data_imu"
        );
        let shape = &json[json.find("\"shape\"").unwrap()..];
        let rows: usize = shape[shape.find('[').unwrap() + 1..shape.find(',').unwrap()]
            .trim()
            .parse()
            .unwrap();
        assert_eq!(d.rows(), rows, "case {case}: rows");
        // The first row's time, printed at 17 significant digits, parses to the same double.
        let first_t: f64 = first_quoted_after(&json, "first_rows").parse().unwrap();
        assert_eq!(d.row(0)[0], first_t, "case {case}: first record time");
    }
}

#[test]
fn other_topics_are_ignored_and_counted() {
    let bag = bag2mat::BagReader::open(&case_bag("p2_medium_100hz")).unwrap();
    let topics = bag.topics();
    let find = |t: &str| topics.iter().find(|s| s.topic == t).unwrap().count;
    assert_eq!(find("/imu/data"), 72000);
    assert_eq!(find("/status"), 720);
}
