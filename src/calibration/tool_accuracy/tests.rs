use super::*;
use crate::calibration::model_parameters::{model_difference, model_displaced, model_parameter_names};
use crate::robot::{CouplingFunction, Transmission};
use nalgebra::DMatrix;
use nalgebra::Vector3;

/// The paper robot's description and a model with every kind of parameter: harmonic and gear
/// transmissions, gear and fractional couplings, placed base and tool (the nominal model with
/// couplings and transmissions from the description's forms, offsets non-zero).
fn robot() -> (RobotDescription, RobotModel) {
    let desc = RobotDescription::asea_irb6l();
    let mut r = RobotModel::ideal(&desc);
    for (k, j) in r.joints.iter_mut().enumerate() {
        j.transducer_offset = 0.01 * (k as f64 + 1.0);
        j.transmission = Transmission::Harmonic {
            sin: vec![1e-3 * k as f64],
            cos: vec![-5e-4],
        };
    }
    r.joints[4].transmission = Transmission::Gear {
        ratio: 1.5,
        sin: vec![2e-3],
        cos: vec![1e-3],
    };
    r.joints[2].coupling_in = Some(CouplingFunction::Fractional {
        num: [0.1, 0.0, 0.0],
        den: [0.0, 0.0],
    });
    r.joints[4].coupling_in = Some(CouplingFunction::Gear {
        ratio: 32.0 / 19.0,
        sin: vec![1e-3],
        cos: vec![0.0],
    });
    r.placement = crate::robot::Placement {
        translation_mm: [1500.0, -200.0, 100.0],
        rpy_deg: [3.0, -2.0, 170.0],
    };
    r.tool_frame = crate::robot::Placement {
        translation_mm: [10.0, 20.0, 150.0],
        rpy_deg: [179.0, 1.0, -90.0],
    };
    (desc, r)
}

/// `model_moved` then `model_difference` gives back the unit vector of the moved parameter:
/// the two are one parameterisation (to first order; the step 1e-7 in m or rad leaves
/// rounding ~1e-16 / 1e-7 ~ 1e-9 of the degrees' and Euler angles' round trip, times the
/// largest stored magnitude ~ 200 deg; 1e-6 bounds it).
#[test]
fn moved_and_difference_are_one_parameterisation() {
    let (_, r) = robot();
    let n = model_parameter_names(&r).len();
    assert_eq!(n, model_difference(&r, &r, 1.0).len());
    let h = 1e-7;
    for k in 0..n {
        let d = model_difference(&model_moved(&r, k, h), &r, h);
        for (i, v) in d.iter().enumerate() {
            let expected = if i == k { 1.0 } else { 0.0 };
            assert!(
                (v - expected).abs() < 1e-6,
                "parameter {k} ({}) component {i}: {v}",
                model_parameter_names(&r)[k]
            );
        }
    }
}

/// A covariance on every parameter: diagonal, 1e-8 (0.1 mm, 0.1 mrad, 1e-4 of a coefficient).
fn diagonal(n: usize) -> DMatrix<f64> {
    DMatrix::from_diagonal_element(n, n, 1e-8)
}

/// The base placement's columns against their analytic form: the tool point `p` moves by
/// `R_B e_k` for a base translation and `R_B (e_k x (B^-1 p))` for a base rotation, the
/// orientation by `R_B e_k` (central differences of a rotation are exact to O(h^2) = 1e-14 of
/// the ~1 m arm; the placement's round trip through mm and Euler angles rounds at
/// `eps * 1500 mm / 2e-4 mm` ~ 2e-9 over the 1e-7 m step: 1e-8 bounds it).
#[test]
fn base_columns_match_the_analytic_jacobian() {
    let (desc, r) = robot();
    let controller = Controller::from_description(&desc);
    let n = model_parameter_names(&r).len();
    let s = ToolSensitivity::new(&r, &controller, &diagonal(n));
    let cmd = commands_to_internal(&desc, &[10.0, -20.0, 15.0, 30.0, -40.0, 50.0]);
    let j = s.jacobian(&cmd).unwrap();
    let base = r.placement.to_isometry();
    let p = base.inverse() * s.tool_point(&cmd).unwrap();
    for k in 0..6 {
        let e = Vector3::ith(k % 3, 1.0);
        let (dp, dr) = if k < 3 {
            (base.rotation * e, Vector3::zeros())
        } else {
            (base.rotation * e.cross(&p.coords), base.rotation * e)
        };
        for i in 0..3 {
            assert!(
                (j[(i, k)] - dp[i]).abs() < 1e-8,
                "column {k} row {i}: {} vs {}",
                j[(i, k)],
                dp[i]
            );
            assert!(
                (j[(i + 3, k)] - dr[i]).abs() < 1e-8,
                "column {k} row {}: {}",
                i + 3,
                j[(i + 3, k)]
            );
        }
    }
}

/// Every column against forward differences with a 10x larger step: the forward error is
/// `h |f''| / 2` with `h = 1e-3 sigma = 1e-7` (m or rad) and `|f''|` at most a few metres
/// per rad^2 (the arm's reach), so ~1e-6 absolute; 1e-5 bounds it.
#[test]
fn every_column_matches_forward_differences() {
    let (desc, r) = robot();
    let controller = Controller::from_description(&desc);
    let n = model_parameter_names(&r).len();
    let s = ToolSensitivity::new(&r, &controller, &diagonal(n));
    let cmd = commands_to_internal(&desc, &[-25.0, 10.0, -5.0, 60.0, 20.0, -70.0]);
    let j = s.jacobian(&cmd).unwrap();
    let at = tool_pose(&r, &controller, &cmd).unwrap();
    let h = 1e-6;
    for k in 0..n {
        let moved = tool_pose(&model_moved(&r, k, h), &controller, &cmd).unwrap();
        let dp = (moved.translation.vector - at.translation.vector) / h;
        let dr = (moved.rotation * at.rotation.inverse()).scaled_axis() / h;
        for i in 0..3 {
            assert!(
                (j[(i, k)] - dp[i]).abs() < 1e-5,
                "column {k} position {i}: {} vs {}",
                j[(i, k)],
                dp[i]
            );
            assert!(
                (j[(i + 3, k)] - dr[i]).abs() < 1e-5,
                "column {k} rotation {i}: {} vs {}",
                j[(i + 3, k)],
                dr[i]
            );
        }
    }
}

/// Only the base's x translation uncertain (1-sigma 0.2 mm): the tool point has exactly that
/// 1-sigma along the base's x axis in the instrument frame, no orientation uncertainty.
#[test]
fn a_base_translation_moves_the_tool_point_by_its_sigma() {
    let (desc, r) = robot();
    let controller = Controller::from_description(&desc);
    let n = model_parameter_names(&r).len();
    let mut c = DMatrix::zeros(n, n);
    c[(0, 0)] = 0.2e-3f64.powi(2);
    let s = ToolSensitivity::new(&r, &controller, &c);
    let sigma = s.sigma_at(&[0.3; 6]).unwrap();
    let x = r.placement.to_isometry().rotation * Vector3::x() * 0.2;
    for i in 0..3 {
        assert!((sigma.position_mm[i] - x[i].abs()).abs() < 1e-9, "{sigma:?}");
    }
    assert!(
        (sigma.position_norm_mm - 0.2).abs() < 1e-9 && sigma.orientation_norm_mrad < 1e-9,
        "{sigma:?}"
    );
}

/// The draws stay in their ranges, a fixed range gives its value, the same seed the same
/// poses; a joint no sweep covers is at the reference.
#[test]
fn poses_are_drawn_in_their_ranges() {
    let ranges = [[-10.0, 20.0], [5.0, 5.0]];
    let poses = draw_poses(&ranges, 50, 3);
    assert_eq!(poses, draw_poses(&ranges, 50, 3));
    // A fixed range returns its bound itself, bit for bit.
    assert!(
        poses
            .iter()
            .all(|p| (-10.0..=20.0).contains(&p[0]) && p[1].to_bits() == 5f64.to_bits())
    );
    assert_eq!(swept_ranges(&[], &[1.0, 2.0]), vec![[1.0, 1.0], [2.0, 2.0]]);
}

/// `model_displaced` by a unit step of one parameter is `model_moved` (to rounding), and by a
/// small vector `d` it is measured back by `model_difference` as `d` to second order: the
/// residual is below `|d|^2` times the largest lever (2 m).
#[test]
fn displaced_is_moved_along_a_whole_vector() {
    let (_, r) = robot();
    let n = model_parameter_names(&r).len();
    let h = 1e-6;
    for k in 0..n {
        let mut d = vec![0.0; n];
        d[k] = h;
        let a = model_difference(&model_displaced(&r, &d), &r, h);
        let b = model_difference(&model_moved(&r, k, h), &r, h);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-6, "parameter {k}: {x} vs {y}");
        }
    }
    let d: Vec<f64> = (0..n).map(|k| 1e-5 * ((k * 7919 % 13) as f64 - 6.0) / 6.0).collect();
    let back = model_difference(&model_displaced(&r, &d), &r, 1.0);
    let norm2: f64 = d.iter().map(|x| x * x).sum();
    for (k, (x, y)) in back.iter().zip(&d).enumerate() {
        assert!((x - y).abs() <= 2.0 * norm2 + 1e-12, "parameter {k}: {x} vs {y}");
    }
}
