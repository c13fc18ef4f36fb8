//! The recorder's tests alone, for the build with the `viz` feature (`cargo test --features viz
//! --test record`): the `cli_record` module of `tests/it/` and its helpers, so that the feature
//! build compiles one module instead of the whole `it` binary, and the recorder's parts
//! (`viz`).
//! Without the feature, `cargo test --test it cli_record::` runs the same module.

#[allow(dead_code)]
#[path = "it/common/mod.rs"]
mod common;

#[path = "it/cli_record.rs"]
mod cli_record;

/// The recorder's parts: the arcs drawn for an axis fit, the robot's boxes and four-bar loop,
/// the colours, and a recording saved and read back. They need the `viz` build, so they run
/// here, beside the recorder's command-line tests, rather than as the library's unit tests (the
/// CI's `viz` step then compiles the library once, not a second time as a test harness).
mod viz {
    use approx::assert_relative_eq;
    use axiscal::calibration::{ArcFitOptions, MeasurementNoise, fit_arc};
    use axiscal::robot::{FourBarGeometry, RobotDescription, TransmissionFitForm};
    use axiscal::viz::*;
    use nalgebra::{Isometry3, Point3, Vector3};

    #[test]
    fn arc_points_lie_on_the_fitted_circle_over_the_swept_range() {
        // An exact arc of radius 0.5 about z through (1, 2, 3), swept over 1 rad.
        let commands: Vec<f64> = (0..8).map(|j| 0.2 + j as f64 / 7.0).collect();
        let centre = Point3::new(1.0, 2.0, 3.0);
        let pts: Vec<Point3<f64>> = commands
            .iter()
            .map(|c| centre + 0.5 * Vector3::new(c.cos(), c.sin(), 0.0))
            .collect();
        let options = ArcFitOptions {
            form: TransmissionFitForm::Harmonic { order: 1 },
            noise: MeasurementNoise::Isotropic { sigma_per_axis: 1e-4 },
            reference_point: centre,
            max_iterations: 50,
        };
        let fit = fit_arc(&pts, &commands, &options).expect("fit");
        let arc = arc_points(&fit, &commands, 16).expect("arc");
        assert_eq!(arc.len(), 16);
        for p in &arc {
            assert_relative_eq!((p - centre).xy().norm(), 0.5, epsilon = 1e-6);
        }
        let ends = [arc[0], arc[15]];
        let firsts = [pts[0], pts[7]];
        let matched = ends.iter().all(|e| firsts.iter().any(|f| (e - f).norm() < 1e-6));
        assert!(matched, "arc ends at the first and last measured points");
    }

    #[test]
    fn boxes_span_their_segments() {
        let pts = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
            Point3::new(-1.0, 2.0, 0.0),
        ];
        let boxes = segment_boxes(&pts, 0.1);
        assert_eq!(boxes.len(), 2, "the zero-length segment is skipped");
        let (c, h, r) = &boxes[0];
        assert_relative_eq!(*c, Point3::new(0.0, 1.0, 0.0), epsilon = 1e-12);
        assert_relative_eq!(h.x, 1.0, epsilon = 1e-12);
        assert_relative_eq!(r * Vector3::x(), Vector3::y(), epsilon = 1e-12);
        let (_, _, r) = &boxes[1];
        assert_relative_eq!(r * Vector3::x(), -Vector3::x(), epsilon = 1e-12);
    }

    #[test]
    fn parallelogram_loop_closes_with_its_nominal_passive_angle() {
        let g = FourBarGeometry::parallelogram(0.7, 0.2, 2.0);
        let frame2 = Isometry3::translation(1.0, 2.0, 3.0);
        let theta_2: f64 = 0.3;
        let axis3 = Point3::new(1.0 + 0.7 * theta_2.cos(), 2.0 + 0.7 * theta_2.sin(), 3.5);
        let passive = g.passive(theta_2).expect("assembles");
        let [o2, c, p, o3, end] = four_bar_loop_m(&g, &frame2, &axis3, theta_2, passive);
        assert_eq!(o2, end);
        assert_relative_eq!((o3 - o2).norm(), g.arm_m, epsilon = 1e-12);
        assert_relative_eq!((c - o2).norm(), g.crank_m, epsilon = 1e-12);
        assert_relative_eq!((p - c).norm(), g.rod_m, epsilon = 1e-9);
        assert_relative_eq!((p - o3).norm(), g.lever_m, epsilon = 1e-12);
        assert_relative_eq!(o3, Point3::new(axis3.x, axis3.y, 3.0), epsilon = 1e-12);
    }

    #[test]
    fn a_saved_recording_is_a_non_empty_rrd_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("x.rrd");
        let desc = RobotDescription::asea_irb6l();
        let model = desc.nominal_model();
        let rec = Recorder::new("axiscal_test").expect("recorder");
        rec.set_trial(0);
        for step in 0..3 {
            rec.set_step(step);
            let q = vec![0.1 * step as f64; desc.dof()];
            rec.log_robot(&model, &q);
            rec.log_targets("axis1", &[model.world_from_tool(&q) * Point3::origin()]);
            rec.log_scalar("residual_mm", step as f64);
        }
        let a = [Point3::new(0.0, 0.0, 0.0)];
        let b = [Point3::new(0.001, 0.0, 0.0)];
        let lengths = rec.log_error_vectors("validation", &a, &b, 0.002, 1.0).expect("arrows");
        approx::assert_relative_eq!(lengths[0], 0.001);
        rec.save(&path).expect("save");
        let bytes = std::fs::read(&path).expect("read back");
        assert!(bytes.len() > 1000, "recording has {} bytes", bytes.len());
        assert_eq!(&bytes[..4], b"RRF2", "rrd magic");
    }

    #[test]
    fn mismatched_error_vectors_are_an_error() {
        let rec = Recorder::new("axiscal_test").expect("recorder");
        let err = rec.log_error_vectors("x", &[Point3::origin()], &[], 1.0, 1.0);
        assert!(matches!(
            err,
            Err(VizError::LengthMismatch {
                expected: 1,
                found: 0,
                ..
            })
        ));
    }

    #[test]
    fn error_colours_follow_the_documented_stops() {
        for (at, rgb) in ERROR_COLOR_STOPS {
            let c = error_color(at * 2.0, 2.0);
            assert_eq!(&c[..3], &rgb[..], "stop at {at}");
        }
        assert_eq!(error_color(5.0, 1.0), error_color(1.0, 1.0), "clamped above full scale");
        assert_eq!(error_color(1.0, 0.0), error_color(1.0, 1.0), "bad scale is red");
        let quarter = error_color(0.25, 1.0);
        assert_eq!(quarter, [120, 185, 30, 255], "halfway between green and yellow");
    }

    #[test]
    fn experiments_get_distinct_stable_colours() {
        let axes: Vec<_> = (1..=6).map(|k| experiment_color(&format!("axis{k}"))).collect();
        for (i, a) in axes.iter().enumerate() {
            for b in &axes[i + 1..] {
                assert_ne!(a, b);
            }
        }
        assert_eq!(experiment_color("custom"), experiment_color("custom"));
        assert_eq!(experiment_color("axis2/target1"), axes[1]);
        assert_ne!(experiment_color("validation"), axes[0]);
    }
}
