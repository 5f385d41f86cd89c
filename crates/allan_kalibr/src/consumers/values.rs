//! The figures a config file carries, whatever their origin: one value per sensor and
//! quantity (N and K, continuous time, as [`super::Quantity`] defines them), per-axis values
//! for a consumer that takes them, which values are bounds or region readings, the caveats
//! every file repeats, and whether the figures were measured or taken from a datasheet.
//! Built from an analysis by `crate::ieee952::config_values`, from a datasheet by
//! [`super::plan`]; rendered per consumer by [`super::render`].

use super::Quantity;

/// One number per sensor for the configuration files.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorValue {
    /// The value.
    pub value: f64,
    /// True when the value is a 95 % upper bound (no axis resolved the term).
    pub upper_bound: bool,
    /// True when the value comes from an IEEE 952 region reading (no reliable fit).
    pub region: bool,
}

/// Where the figures come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Measured: this tool's IEEE 952 analysis of a record.
    Measured,
    /// Converted from datasheet figures (`allan_kalibr plan`): not measured.
    Datasheet,
}

/// One axis' value of a quantity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisValue {
    /// The value (continuous time).
    pub value: f64,
    /// True when it is a 95 % upper bound (the axis does not resolve the term).
    pub upper_bound: bool,
}

/// The figures of a config file.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigValues {
    /// One value per quantity, in [`Quantity::ALL`] order; `None`: left out (the sensor is
    /// absent, or nothing is known of it).
    pub values: [Option<SensorValue>; 4],
    /// Per axis x y z, in [`Quantity::ALL`] order (Basalt takes them); `None` when the sensor
    /// is absent or an axis has no value.
    pub axes: [Option<[AxisValue; 3]>; 4],
    /// Caveats every file carries as comments (fit, record check, origin).
    pub comments: Vec<String>,
    /// Measured or from a datasheet.
    pub origin: Origin,
}

impl ConfigValues {
    /// Plain figures (`None` leaves a quantity out), the same on every axis, with `origin`
    /// and no caveat: a datasheet's figures, or values for tests.
    pub fn plain(values: [Option<f64>; 4], origin: Origin) -> ConfigValues {
        let v = |x: Option<f64>| {
            x.map(|value| SensorValue {
                value,
                upper_bound: false,
                region: false,
            })
        };
        let a = |x: Option<f64>| {
            x.map(|value| {
                [AxisValue {
                    value,
                    upper_bound: false,
                }; 3]
            })
        };
        ConfigValues {
            values: values.map(v),
            axes: values.map(a),
            comments: Vec::new(),
            origin,
        }
    }

    /// The value of `q`.
    pub fn get(&self, q: Quantity) -> Option<SensorValue> {
        self.values[q.index()]
    }

    /// The per-axis values of `q`.
    pub fn axes(&self, q: Quantity) -> Option<[AxisValue; 3]> {
        self.axes[q.index()]
    }
}

/// The comment a key gets when its value is not a plain fitted value.
pub(crate) fn key_note(key: &str, v: Option<SensorValue>) -> Option<String> {
    let v = v?;
    match (v.upper_bound, v.region) {
        (true, false) => Some(format!(
            "{key} is NOT RESOLVED by this record: 95 % upper bound."
        )),
        (true, true) => Some(format!(
            "{key} is NOT RESOLVED (no reliable fit; IEEE 952 region rule): 95 % upper bound."
        )),
        (false, true) => Some(format!(
            "{key} is an IEEE 952 region reading: the model did not fit an axis."
        )),
        (false, false) => None,
    }
}

/// The end-of-line note of a value that is a bound or a region reading ("" otherwise).
pub(crate) fn inline_note(v: Option<SensorValue>) -> &'static str {
    match v {
        Some(SensorValue {
            upper_bound: true, ..
        }) => " NOT RESOLVED: 95 % upper bound",
        Some(SensorValue { region: true, .. }) => " IEEE 952 region reading (no reliable fit)",
        _ => "",
    }
}
