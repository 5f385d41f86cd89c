//! Rotation-matrix ↔ quaternion conversions with Eigen's sign rule, so quaternions printed to
//! the text files have the same signs as upstream's (docs/upstream/vio_data_simulation.md §5, §8 item 4).

use nalgebra::{Matrix3, Quaternion, UnitQuaternion};

/// Quaternion `[w, x, y, z]` of a rotation matrix by Eigen's `Quaternion(Matrix3)` rule
/// (Shoemake): if the trace is positive, w > 0; otherwise the component with the largest
/// diagonal entry is made positive — so w can be negative and the sign can jump along a
/// smooth trajectory (upstream files do, e.g. at t ≈ 13.365 s; docs/upstream/vio_data_simulation.md §5).
pub fn quat_from_matrix(m: &Matrix3<f64>) -> [f64; 4] {
    let trace = m[(0, 0)] + m[(1, 1)] + m[(2, 2)];
    if trace > 0.0 {
        let s = (trace + 1.0).sqrt();
        let w = 0.5 * s;
        let s = 0.5 / s;
        [
            w,
            (m[(2, 1)] - m[(1, 2)]) * s,
            (m[(0, 2)] - m[(2, 0)]) * s,
            (m[(1, 0)] - m[(0, 1)]) * s,
        ]
    } else {
        let mut i = 0;
        if m[(1, 1)] > m[(0, 0)] {
            i = 1;
        }
        if m[(2, 2)] > m[(i, i)] {
            i = 2;
        }
        let j = (i + 1) % 3;
        let k = (j + 1) % 3;
        let s = (m[(i, i)] - m[(j, j)] - m[(k, k)] + 1.0).sqrt();
        let mut v = [0.0; 3];
        v[i] = 0.5 * s;
        let s = 0.5 / s;
        let w = (m[(k, j)] - m[(j, k)]) * s;
        v[j] = (m[(j, i)] + m[(i, j)]) * s;
        v[k] = (m[(k, i)] + m[(i, k)]) * s;
        [w, v[0], v[1], v[2]]
    }
}

/// nalgebra unit quaternion from `[w, x, y, z]` (normalised).
pub fn unit_quat(q: [f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
}

/// Rotation matrix of `[w, x, y, z]` (normalised first).
pub fn matrix_from_quat(q: [f64; 4]) -> Matrix3<f64> {
    unit_quat(q).to_rotation_matrix().into_inner()
}
