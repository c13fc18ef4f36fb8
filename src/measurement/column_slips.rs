//! The column slips a measurement file's free poses can carry, each as a rewrite of a row that
//! undoes it: a command column in radians (metres for a sliding joint) or gradians, negated,
//! halved or doubled; two command columns swapped; a coordinate column in another length unit
//! ([`LENGTH_SLIPS`]) or negated; two coordinate columns swapped. The free-pose calibration
//! tries each on its poses before it blames the description (`calibrate` on a file of free
//! poses), and the validation's slip search tries them on the rows a calibration misses
//! (`crate::diagnosis`'s `slips`): one list, one naming. No maths beyond the rewrite: whoever
//! tries them judges the fit.

use super::Measurement;
use super::unit_check::LENGTH_SLIPS;
use crate::kinematics::JointKind;

/// A slip is searched for, or said, only beyond this many times its test's acceptance (the
/// bound the noise and the predicted error give at the test's false-alarm rate): a slip moves
/// the points by millimetres to metres where a calibration predicts tenths; a nearer miss is
/// the model's (an effect `diagnose` looks for: sag, backlash, a gear's error), and a rewrite
/// that changes the predictions a little could pass the acceptance by chance. One factor for
/// `validate`'s slip search (`crate::diagnosis`'s `slips`, `sweep_slips`) and `calibrate`'s
/// test of the sweeps' shared target ([`crate::calibration::shared_target`]).
pub const GROSS_MISS_FACTOR: f64 = 3.0;

/// Gradians per degree: a command column written in gradians reads 400/360 of the degrees.
const GRADIANS_PER_DEGREE: f64 = 400.0 / 360.0;

/// One slip of a file's columns and the rewrite of a row that undoes it.
pub struct ColumnSlip {
    /// The column (or columns) it names: `cmd_2`, `x_mm,y_mm`.
    pub field: String,
    /// What the data then are: "`cmd_2` is negated (its joint's positive direction reversed)".
    pub claim: String,
    /// How the rows are read with the slip undone: "with `cmd_2` negated".
    pub reading: String,
    /// The rewrite of one row that undoes the slip.
    pub undo: Box<dyn Fn(&mut Measurement) + Send + Sync>,
    /// Whether it mirrors the coordinates (a column negated, two swapped): every mirror is
    /// every other one turned, so a fit that places the points rigidly cannot tell them apart.
    pub mirror: bool,
}

/// A slip of `field`, its `claim` and `reading`, undone by `undo`.
pub fn slip(
    field: String,
    [claim, reading]: [String; 2],
    undo: impl Fn(&mut Measurement) + Send + Sync + 'static,
) -> ColumnSlip {
    ColumnSlip {
        field,
        claim,
        reading,
        undo: Box::new(undo),
        mirror: false,
    }
}

fn mirror(field: String, words: [String; 2], undo: impl Fn(&mut Measurement) + Send + Sync + 'static) -> ColumnSlip {
    ColumnSlip {
        mirror: true,
        ..slip(field, words, undo)
    }
}

/// The command columns' slips of a robot whose joints are `kinds` (module docs).
pub fn command_slips(kinds: &[JointKind]) -> Vec<ColumnSlip> {
    let mut out = Vec::new();
    for (k, kind) in kinds.iter().enumerate() {
        let c = format!("`cmd_{}`", k + 1);
        let field = format!("cmd_{}", k + 1);
        let (unit, factor, other) = match kind {
            JointKind::Revolute => ("degrees", 180.0 / std::f64::consts::PI, "radians"),
            JointKind::Prismatic => ("millimetres", 1e3, "metres"),
        };
        let mut scaled = vec![
            (
                factor,
                [
                    format!("{c} holds {other} rather than {unit}"),
                    format!("with {c} read as {other}"),
                ],
            ),
            (
                -1.0,
                [
                    format!("{c} is negated (its joint's positive direction reversed)"),
                    format!("with {c} negated"),
                ],
            ),
            (0.5, [format!("{c} holds twice the {unit}"), format!("with {c} halved")]),
            (2.0, [format!("{c} holds half the {unit}"), format!("with {c} doubled")]),
        ];
        if *kind == JointKind::Revolute {
            scaled.push((
                1.0 / GRADIANS_PER_DEGREE,
                [
                    format!("{c} holds gradians rather than degrees"),
                    format!("with {c} read as gradians"),
                ],
            ));
        }
        for (f, words) in scaled {
            out.push(slip(field.clone(), words, move |m| m.cmd[k] *= f));
        }
        for b in k + 1..kinds.len() {
            out.push(slip(
                format!("cmd_{},cmd_{}", k + 1, b + 1),
                [
                    format!("{c} and `cmd_{}` are swapped", b + 1),
                    format!("with {c} and `cmd_{}` swapped back", b + 1),
                ],
                move |m| m.cmd.swap(k, b),
            ));
        }
    }
    out
}

/// The coordinate columns' slips (module docs).
pub fn coordinate_slips() -> Vec<ColumnSlip> {
    const NAMES: [&str; 3] = ["x_mm", "y_mm", "z_mm"];
    let mut out = Vec::new();
    for (c, name) in NAMES.iter().enumerate() {
        for &(ratio, unit) in LENGTH_SLIPS {
            let words = [
                format!("`{name}` holds {unit} rather than millimetres"),
                format!("with `{name}` read as {unit}"),
            ];
            out.push(slip((*name).into(), words, move |m| m.position_mm[c] /= ratio));
        }
        let words = [format!("`{name}` is negated"), format!("with `{name}` negated")];
        out.push(mirror((*name).into(), words, move |m| {
            m.position_mm[c] = -m.position_mm[c]
        }));
        for (d, other) in NAMES.iter().enumerate().skip(c + 1) {
            out.push(mirror(
                format!("{name},{other}"),
                [
                    format!("`{name}` and `{other}` are swapped"),
                    format!("with `{name}` and `{other}` swapped back"),
                ],
                move |m| m.position_mm.swap(c, d),
            ));
        }
    }
    out
}

/// Every slip of [`command_slips`] and [`coordinate_slips`].
pub fn column_slips(kinds: &[JointKind]) -> Vec<ColumnSlip> {
    let mut out = command_slips(kinds);
    out.extend(coordinate_slips());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_slip_rewrites_its_column_only() {
        let kinds = [JointKind::Revolute, JointKind::Prismatic];
        let row = Measurement {
            experiment: "validation".into(),
            moved_joint: 0,
            step: 0,
            target: 0,
            position_mm: [1.0, 2.0, 3.0],
            cmd: vec![10.0, 20.0],
            payload_kg: 0.0,
            temperature_c: 20.0,
        };
        let slips = column_slips(&kinds);
        // cmd_1: 5 scalings and one swap; cmd_2: 4 scalings; per coordinate 4 units, a sign.
        assert_eq!(slips.len(), 6 + 4 + 3 * (LENGTH_SLIPS.len() + 1) + 3);
        for s in &slips {
            let mut m = row.clone();
            (s.undo)(&mut m);
            assert_ne!(m, row, "{} changes nothing", s.claim);
            assert!(s.reading.starts_with("with "), "{}", s.reading);
            let cmd_changed = m.cmd != row.cmd;
            assert_eq!(cmd_changed, s.field.starts_with("cmd"), "{}", s.claim);
        }
        let grad = slips.iter().find(|s| s.claim.contains("gradians")).unwrap();
        let mut m = row.clone();
        (grad.undo)(&mut m);
        assert!((m.cmd[0] - 9.0).abs() < 1e-12);
    }
}
