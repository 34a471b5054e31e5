//! Out-of-range settings and malformed inputs are refused with a typed error that names the
//! setting, the value and what is allowed, not a free-form string.

use crackbot_vision::classical::ClassicalParams;
use crackbot_vision::fusion::FusionParams;
use crackbot_vision::pixel::PixelEvaluator;
use crackbot_vision::preprocess::Letterbox;
use crackbot_vision::VisionError;

/// The setting a [`VisionError::Setting`] names, or a panic naming what came instead.
fn setting_field(result: Result<(), VisionError>) -> &'static str {
    match result {
        Err(VisionError::Setting { field, .. }) => field,
        Err(other) => panic!("expected VisionError::Setting, got {other:?}"),
        Ok(()) => panic!("expected VisionError::Setting, got Ok"),
    }
}

#[test]
fn a_classical_detector_parameter_out_of_range_is_named() {
    assert!(ClassicalParams::default().validate().is_ok());
    let p = ClassicalParams {
        blur_sigma: 80.0,
        ..ClassicalParams::default()
    };
    assert_eq!(setting_field(p.validate()), "blur_sigma");
    let p = ClassicalParams {
        merge_fraction: f32::NAN,
        ..ClassicalParams::default()
    };
    assert_eq!(setting_field(p.validate()), "merge_fraction");
    let p = ClassicalParams {
        line_radius: 0,
        ..ClassicalParams::default()
    };
    assert_eq!(setting_field(p.validate()), "line_radius");
}

#[test]
fn fusion_iou_and_pixel_tolerance_are_checked_with_their_range() {
    let fusion = FusionParams {
        iou: 1.5,
        ..FusionParams::default()
    };
    let err = fusion.validate().unwrap_err();
    let text = err.to_string();
    assert!(
        matches!(err, VisionError::Setting { field: "fusion iou", value, allowed: "in [0, 1]" } if value == 1.5),
        "{err:?}"
    );
    assert!(
        text.contains("fusion iou") && text.contains("1.5") && text.contains("[0, 1]"),
        "{text}"
    );
    let tolerance = PixelEvaluator::new(-2.0).map(|_| ());
    assert_eq!(setting_field(tolerance), "pixel tolerance_px");
    assert!(PixelEvaluator::new(2.0).is_ok());
}

#[test]
fn empty_images_and_wrong_shapes_are_their_own_errors() {
    assert!(matches!(
        Letterbox::new(0, 480, 320),
        Err(VisionError::EmptyImage {
            width: 0,
            height: 480
        })
    ));
    assert_eq!(
        setting_field(Letterbox::new(640, 480, 0).map(|_| ())),
        "input size"
    );
    let mut evaluator = PixelEvaluator::new(2.0).expect("a valid tolerance");
    let err = evaluator.add(&[0.5; 12], &[false; 11], 4, 3).unwrap_err();
    assert!(
        matches!(
            err,
            VisionError::Shape {
                what: "the mask",
                got: 11,
                expected: 12
            }
        ),
        "{err:?}"
    );
    let mut map = [0.5f32; 12];
    map[7] = 1.5;
    let err = evaluator.add(&map, &[false; 12], 4, 3).unwrap_err();
    assert!(
        matches!(err, VisionError::NotProbability { value } if value == 1.5),
        "{err:?}"
    );
    assert!(evaluator.add(&[0.5; 12], &[false; 12], 4, 3).is_ok());
}
