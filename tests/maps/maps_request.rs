//! The parameter-source request (src/maps/request.rs): each input rule refuses a bad input with an error naming it,
//! and a good request becomes the planes (from memory) or the reader's inputs (from files).

use std::path::PathBuf;

use spectral_skin::maps::io::{write_channels_exr, ExrOptions, ParamInputs, ParamSource, Plane};
use spectral_skin::maps::request::{Combined, ParamRequest, Source, Texels};
use spectral_skin::skin::params::{
    BLOOD_OXYGENATION, EPIDERMIS_THICKNESS, HEMOGLOBIN, MELANIN, MELANIN_BLEND, OILINESS, PAPER_PARAMS,
};
use spectral_skin::SkinError;

fn texels(width: usize, height: usize, value: f32) -> Source {
    Source::Texels(Texels { width, height, values: vec![value; width * height] })
}

/// Valid constants for the four but melanin, and a (2, 3) melanin map.
fn four(melanin: Source) -> ParamRequest {
    ParamRequest::new(None)
        .with(&MELANIN, melanin)
        .with(&MELANIN_BLEND, Source::Constant(0.5))
        .with(&HEMOGLOBIN, Source::Constant(0.02))
        .with(&OILINESS, Source::Constant(0.3))
}

fn message(r: Result<impl std::fmt::Debug, SkinError>) -> String {
    r.unwrap_err().to_string()
}

#[test]
fn each_of_the_four_needs_a_source_and_the_error_lists_the_missing() {
    let request = ParamRequest::new(None).with(&MELANIN, texels(2, 2, 0.1)).with(&MELANIN_BLEND, Source::Constant(0.5));
    let e = message(request.check(false));
    assert!(e.contains("missing: hemoglobin, oiliness") && e.contains("params"), "{e}");
    assert!(!e.contains("missing: melanin"), "{e}");
    let e = message(ParamRequest::default().check(false));
    assert!(e.contains("missing: melanin, melanin_blend, hemoglobin, oiliness"), "{e}");
    // The four-channel input gives each a channel; an extended parameter needs none.
    let combined = ParamRequest::new(Some(Combined::File(PathBuf::from("face.exr"))));
    assert_eq!(combined.check(false), Ok(()));
}

#[test]
fn an_array_channel_left_out_is_missing_unless_its_parameter_has_a_source() {
    let planes = [Some(vec![0.1; 4]), Some(vec![0.5; 4]), None, Some(vec![0.3; 4])];
    let request = ParamRequest::new(Some(Combined::Texels { width: 2, height: 2, planes }));
    let e = message(request.clone().check(false));
    assert!(e.contains("missing: hemoglobin"), "{e}");
    assert_eq!(request.with(&HEMOGLOBIN, Source::Constant(0.01)).check(false), Ok(()));
}

#[test]
fn constants_alone_have_no_map_size() {
    let e = message(four(Source::Constant(0.1)).check(false));
    assert!(e.contains("at least one map") && e.contains("at least one array") && e.contains("constant"), "{e}");
    let e = message(four(Source::Constant(0.1)).into_image(false));
    assert!(e.contains("at least one map"), "{e}");
}

#[test]
fn maps_in_memory_must_agree_in_shape_and_the_error_lists_each() {
    let request = four(texels(3, 2, 0.1)).with(&OILINESS, texels(2, 3, 0.3));
    let e = message(request.check(false));
    assert!(e.contains("shapes") && e.contains("melanin (2, 3)") && e.contains("oiliness (3, 2)"), "{e}");
    let planes = [Some(vec![0.1; 64]), Some(vec![0.5; 64]), Some(vec![0.01; 64]), Some(vec![0.3; 64])];
    let request = ParamRequest::new(Some(Combined::Texels { width: 8, height: 8, planes }))
        .with(&EPIDERMIS_THICKNESS, texels(4, 4, 0.2));
    let e = message(request.check(false));
    assert!(e.contains("params (8, 8, 4)") && e.contains("epidermis_thickness_mm (4, 4)"), "{e}");
}

#[test]
fn an_empty_map_is_refused_naming_its_size() {
    let e = message(four(Source::Texels(Texels { width: 8, height: 0, values: Vec::new() })).check(false));
    assert!(e.contains("8 wide x 0 high"), "{e}");
}

#[test]
fn a_constant_out_of_range_names_the_parameter_range_and_value_unless_clamped() {
    let request = four(texels(2, 2, 0.1)).with(&HEMOGLOBIN, Source::Constant(0.2));
    let error = request.check(false).unwrap_err();
    assert_eq!(error, SkinError::BadConstant { parameter: "hemoglobin", min: 0.0, max: 0.1, value: 0.2 });
    let e = error.with_clamp_advice("use --clamp");
    assert!(
        e.contains("hemoglobin") && e.contains("[0, 0.1]") && e.contains("0.2") && e.contains("use --clamp"),
        "{e}"
    );
    let nan = four(texels(2, 2, 0.1)).with(&BLOOD_OXYGENATION, Source::Constant(f64::NAN));
    assert!(message(nan.check(false)).contains("blood_oxygenation"));
    // Clamping: the constant passes here (the planes' check clamps and reports it).
    assert_eq!(request.check(true), Ok(()));
    let image = request.into_image(true).unwrap();
    assert_eq!(image.planes[2], Plane::Constant(0.2));
}

#[test]
fn from_memory_the_planes_are_the_sources_and_the_extended_physiology_defaults() {
    let planes = [Some(vec![0.1; 6]), None, Some(vec![0.02; 6]), Some(vec![0.3; 6])];
    let request = ParamRequest::new(Some(Combined::Texels { width: 3, height: 2, planes }))
        .with(&MELANIN_BLEND, texels(3, 2, 0.7))
        .with(&BLOOD_OXYGENATION, Source::Constant(0.9));
    let image = request.into_image(false).unwrap();
    assert_eq!((image.width, image.height), (3, 2));
    assert_eq!(image.planes[0], Plane::Texels(vec![0.1; 6]));
    assert_eq!(image.planes[1], Plane::Texels(vec![0.7; 6]));
    assert_eq!(image.extended[0], Plane::Constant(EPIDERMIS_THICKNESS.default.unwrap() as f32));
    assert_eq!(image.extended[2], Plane::Constant(0.9));
}

#[test]
fn files_become_the_readers_inputs() {
    let request = ParamRequest::new(Some(Combined::File(PathBuf::from("face.exr"))))
        .with(&HEMOGLOBIN, Source::Constant(0.05))
        .with(&EPIDERMIS_THICKNESS, Source::File(PathBuf::from("thickness.png")));
    let inputs = request.file_inputs(false).unwrap();
    let ParamInputs::Extended { inputs, extended } = inputs else { panic!("{inputs:?}") };
    assert_eq!(*inputs, ParamInputs::Multi { path: "face.exr".into(), constants: [None, None, Some(0.05), None] });
    assert_eq!(extended, [Some(ParamSource::File("thickness.png".into())), None, None]);
    // Per parameter: each of the four its file or constant.
    let separate = four(Source::File(PathBuf::from("m.png"))).file_inputs(false).unwrap();
    let ParamInputs::Extended { inputs, .. } = separate else { panic!() };
    let ParamInputs::Separate(sources) = *inputs else { panic!("{inputs:?}") };
    assert_eq!(sources[0], ParamSource::File("m.png".into()));
    assert_eq!(sources[3], ParamSource::Constant(0.3));
    // The rules come first.
    let bad = four(Source::File(PathBuf::from("m.png"))).with(&OILINESS, Source::Constant(2.0));
    assert!(matches!(bad.file_inputs(false), Err(SkinError::BadConstant { parameter: "oiliness", .. })));
}

#[test]
fn a_map_file_cannot_replace_a_channel_of_the_params_file_nor_texels_be_read_as_files() {
    let request = ParamRequest::new(Some(Combined::File(PathBuf::from("face.exr"))))
        .with(&MELANIN, Source::File(PathBuf::from("m.png")));
    let e = message(request.file_inputs(false));
    assert!(e.contains("melanin") && e.contains("params file"), "{e}");
    let e = message(four(texels(2, 2, 0.1)).file_inputs(false));
    assert!(e.contains("melanin") && e.contains("memory"), "{e}");
}

#[test]
fn a_map_in_memory_beside_files_must_have_their_size() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.exr");
    write_channels_exr(&path, 4, 2, &[("Y", &[0.1; 8])], ExrOptions::FLOAT_PIZ).unwrap();
    let image = four(Source::File(path.clone())).with(&OILINESS, texels(4, 2, 0.4)).into_image(false).unwrap();
    assert_eq!(image.planes[0], Plane::Texels(vec![0.1; 8]));
    assert_eq!(image.planes[3], Plane::Texels(vec![0.4; 8]));
    let e = message(four(Source::File(path)).with(&OILINESS, texels(2, 2, 0.4)).into_image(false));
    assert!(e.contains("shapes") && e.contains("(2, 2)") && e.contains("(2, 4)"), "{e}");
}

#[test]
fn a_source_is_found_by_its_parameter() {
    let request = four(texels(2, 2, 0.1));
    for spec in PAPER_PARAMS {
        assert!(request.source(&spec).is_some(), "{}", spec.name);
    }
    assert_eq!(request.source(&EPIDERMIS_THICKNESS), None);
}
