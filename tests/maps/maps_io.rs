//! Parameter-map reading and atomic EXR/bytes writing (src/maps/io/).

use std::path::Path;

use spectral_skin::maps::io::{
    commit_all, default_extended, read_exr_channels, read_params, read_params_from_bytes, stage_bytes, stage_rgb_exr,
    write_atomic, write_channels_exr, write_rgb_exr, Compression, ExrOptions, ParamImage, ParamInputs, ParamSource,
    Plane, Precision, ALL_COMPRESSIONS, ALL_PRECISIONS, PARAM_CHANNELS, PARAM_RANGES,
};

/// Every precision with every compression.
fn all_options() -> Vec<ExrOptions> {
    ALL_PRECISIONS
        .iter()
        .flat_map(|&precision| ALL_COMPRESSIONS.iter().map(move |&compression| ExrOptions { precision, compression }))
        .collect()
}

/// Sorted file names in a directory (temporary files included: they start with a dot).
fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

/// A deterministic plane with distinct values per texel, some negative and some large.
fn plane(width: usize, height: usize, seed: f32) -> Vec<f32> {
    (0..width * height).map(|i| ((i as f32) * 0.37 + seed).sin() * (1.0 + seed) + (i % 7) as f32 * 0.01).collect()
}

fn as_stored(values: &[f32], precision: Precision) -> Vec<f32> {
    if precision == Precision::Half {
        values.iter().map(|&v| half::f16::from_f32(v).to_f32()).collect()
    } else {
        values.to_vec()
    }
}

fn texels(p: &Plane) -> &[f32] {
    match p {
        Plane::Texels(v) => v,
        Plane::Constant(c) => panic!("expected texels, got constant {c}"),
    }
}

fn err_text<T: std::fmt::Debug>(r: Result<T, spectral_skin::SkinError>) -> String {
    r.unwrap_err().to_string()
}

fn file(p: &Path) -> ParamSource {
    ParamSource::File(p.to_path_buf())
}

fn save_l8(path: &Path, width: u32, height: u32, data: Vec<u8>) {
    image::GrayImage::from_raw(width, height, data).unwrap().save(path).unwrap();
}

fn save_l16(path: &Path, width: u32, height: u32, data: Vec<u16>) {
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(width, height, data).unwrap().save(path).unwrap();
}

fn mapped(p: usize, v: f64, full_scale: f64) -> f32 {
    let (min, max) = PARAM_RANGES[p];
    (min + (max - min) * v / full_scale) as f32
}

#[test]
fn multi_channel_exr_round_trips_in_every_encoding() {
    let dir = tempfile::tempdir().unwrap();
    // 41 x 70: several ZIP (16-line) and PIZ (32-line) blocks, the last one partial.
    let (w, h) = (41, 70);
    let planes: Vec<Vec<f32>> = (0..4).map(|k| plane(w, h, k as f32)).collect();
    for (n, options) in all_options().iter().enumerate() {
        let path = dir.path().join(format!("params{n}.exr"));
        let channels: Vec<(&str, &[f32])> =
            PARAM_CHANNELS.iter().zip(&planes).map(|(n, p)| (*n, p.as_slice())).collect();
        write_channels_exr(&path, w, h, &channels, *options).unwrap();
        let img = read_params(&ParamInputs::Multi { path: path.clone(), constants: [None; 4] }).unwrap();
        assert_eq!((img.width, img.height), (w, h), "{options:?}");
        for (k, expected) in planes.iter().enumerate() {
            assert_eq!(texels(&img.planes[k]), as_stored(expected, options.precision).as_slice(), "{options:?} {k}");
        }
        // The generic reader gives the channels sorted by name, with their sample type converted to f32.
        let (rw, rh, chans) = read_exr_channels(&path).unwrap();
        assert_eq!((rw, rh), (w, h), "{options:?}");
        let names: Vec<&str> = chans.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["hemoglobin", "melanin", "melanin_blend", "oiliness"], "{options:?}");
        assert_eq!(chans[1].1, as_stored(&planes[0], options.precision), "{options:?}");
    }
    // Only the finished files are left.
    assert_eq!(names_in(dir.path()).len(), all_options().len());
}

#[test]
fn rgb_exr_round_trips_with_row_0_at_the_top() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (5, 3);
    let r: Vec<f32> = (0..w * h).map(|i| i as f32).collect(); // value = row-major index
    let g: Vec<f32> = (0..w * h).map(|i| (i / w) as f32).collect(); // row number
    let b: Vec<f32> = (0..w * h).map(|i| (i % w) as f32 * 0.5).collect(); // column
    for options in all_options() {
        let path = dir.path().join("albedo.exr");
        write_rgb_exr(&path, w, h, [&r, &g, &b], options).unwrap();
        let (rw, rh, chans) = read_exr_channels(&path).unwrap();
        assert_eq!((rw, rh), (w, h), "{options:?}");
        let get = |name: &str| chans.iter().find(|(n, _)| n == name).unwrap().1.clone();
        assert_eq!(get("R"), r, "{options:?}");
        assert_eq!(get("G"), g, "{options:?}");
        assert_eq!(get("B"), b, "{options:?}");
        // On disk the channels are sorted: B, G, R.
        let names: Vec<&str> = chans.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["B", "G", "R"], "{options:?}");
    }
    // The file is a standard single-part scan-line EXR that the exr crate's own RGBA reader opens,
    // with the sample type and compression asked for.
    let path = dir.path().join("radius.exr");
    write_rgb_exr(&path, w, h, [&r, &g, &b], ExrOptions { precision: Precision::Half, compression: Compression::Piz })
        .unwrap();
    let meta = exr::meta::MetaData::read_from_file(&path, true).unwrap();
    assert_eq!(meta.headers.len(), 1);
    let header = &meta.headers[0];
    assert_eq!(header.compression, exr::compression::Compression::PIZ);
    assert!(
        header.channels.list.iter().all(|c| c.sample_type == exr::meta::attribute::SampleType::F16),
        "{:?}",
        header.channels.list.iter().map(|c| (&c.name, c.sample_type)).collect::<Vec<_>>()
    );
    assert_eq!(header.layer_size.0, w);
    assert_eq!(header.shared_attributes.display_window.size.0, w);
    let rgba = exr::prelude::read_first_rgba_layer_from_file(
        &path,
        |res, _| vec![[0.0f32; 3]; res.width() * res.height()],
        move |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.y() * w + pos.x()] = [r, g, b],
    )
    .unwrap();
    let px = &rgba.layer_data.channel_data.pixels;
    assert_eq!(px[7], [7.0, 1.0, 1.0]);
    assert_eq!(px[14], [14.0, 2.0, 2.0]);
    assert_eq!(names_in(dir.path()), ["albedo.exr", "radius.exr"]);
}

#[test]
fn multi_channel_constants_fill_missing_channels_and_override_present_ones() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("partial.exr");
    let (w, h) = (4, 2);
    let mel = plane(w, h, 0.0);
    let hem = plane(w, h, 2.0);
    let oil = plane(w, h, 3.0);
    write_channels_exr(
        &path,
        w,
        h,
        &[("melanin", &mel), ("hemoglobin", &hem), ("oiliness", &oil)],
        ExrOptions::FLOAT_PIZ,
    )
    .unwrap();
    let img = read_params(&ParamInputs::Multi { path: path.clone(), constants: [None, Some(0.7), None, Some(0.25)] })
        .unwrap();
    assert_eq!(texels(&img.planes[0]), mel.as_slice());
    assert_eq!(img.planes[1], Plane::Constant(0.7));
    assert_eq!(texels(&img.planes[2]), hem.as_slice());
    assert_eq!(img.planes[3], Plane::Constant(0.25), "a constant overrides the file's channel");
    assert_eq!(img.texel(5), [mel[5], 0.7, hem[5], 0.25]);
}

#[test]
fn missing_channel_lists_the_channels_found() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("partial.exr");
    let v = vec![0.1f32; 6];
    write_channels_exr(&path, 3, 2, &[("melanin", &v), ("hemoglobin", &v), ("Y", &v)], ExrOptions::FLOAT_PIZ).unwrap();
    let e = err_text(read_params(&ParamInputs::Multi { path: path.clone(), constants: [None; 4] }));
    assert!(e.contains(&path.display().to_string()), "{e}");
    assert!(e.contains("melanin_blend") && e.contains("oiliness"), "{e}");
    assert!(e.contains("found channels: Y, hemoglobin, melanin"), "{e}");
    assert_eq!(names_in(dir.path()), ["partial.exr"]);
}

#[test]
fn single_channel_exrs_of_any_sample_type_and_layout() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (67, 35);
    let mel = plane(w, h, 0.5);
    let blend = plane(w, h, 1.5);
    // A half-float file with one channel named "Y".
    let p_mel = dir.path().join("mel.exr");
    write_channels_exr(
        &p_mel,
        w,
        h,
        &[("Y", &mel)],
        ExrOptions { precision: Precision::Half, compression: Compression::Zip },
    )
    .unwrap();
    // A multi-channel file used as a separate source: the channel named like the parameter is taken.
    let p_blend = dir.path().join("blend.exr");
    write_channels_exr(&p_blend, w, h, &[("R", &mel), ("melanin_blend", &blend)], ExrOptions::FLOAT_PIZ).unwrap();
    // A tiled, u32, offset-data-window file written by the exr crate directly.
    let p_hem = dir.path().join("hem.exr");
    {
        use exr::prelude::*;
        let values: Vec<u32> = (0..w * h).map(|i| i as u32).collect();
        let channel = AnyChannel::new("hem", FlatSamples::U32(values));
        let layer = Layer::new(
            (w, h),
            LayerAttributes::named("params").with_position(Vec2(10, -4)),
            Encoding {
                compression: exr::compression::Compression::RLE,
                blocks: Blocks::Tiles(Vec2(16, 16)),
                line_order: LineOrder::Decreasing,
            },
            AnyChannels::sort(SmallVec::from_vec(vec![channel])),
        );
        Image::from_layer(layer).write().to_file(&p_hem).unwrap();
    }
    let img =
        read_params(&ParamInputs::Separate([file(&p_mel), file(&p_blend), file(&p_hem), ParamSource::Constant(0.3)]))
            .unwrap();
    assert_eq!((img.width, img.height), (w, h));
    assert_eq!(texels(&img.planes[0]), as_stored(&mel, Precision::Half).as_slice());
    assert_eq!(texels(&img.planes[1]), blend.as_slice());
    let hem: Vec<f32> = (0..w * h).map(|i| i as f32).collect();
    assert_eq!(texels(&img.planes[2]), hem.as_slice());
    assert_eq!(img.planes[3], Plane::Constant(0.3));

    // A multi-channel file without a channel named like the parameter is refused, unless it is a grey RGB image
    // (tests/maps/image_inputs.rs): this one's channels differ.
    let p_rgb = dir.path().join("rgb.exr");
    write_rgb_exr(&p_rgb, w, h, [&mel, &blend, &mel], ExrOptions::FLOAT_PIZ).unwrap();
    let e = err_text(read_params(&ParamInputs::Separate([
        file(&p_rgb),
        ParamSource::Constant(0.5),
        ParamSource::Constant(0.01),
        ParamSource::Constant(0.3),
    ])));
    assert!(e.contains("rgb.exr") && e.contains("single-channel") && e.contains("found channels R, G, B"), "{e}");
    assert!(e.contains("not grey"), "{e}");
}

#[test]
fn png_and_tiff_values_map_onto_parameter_ranges() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (4u32, 2u32);
    // 8-bit PNG, melanin 0..0.5.
    let p8 = dir.path().join("melanin.png");
    save_l8(&p8, w, h, vec![0, 51, 128, 255, 255, 0, 1, 254]);
    // 16-bit PNG, hemoglobin 0..0.1.
    let p16 = dir.path().join("hemoglobin.png");
    save_l16(&p16, w, h, vec![0, 65535, 32768, 1, 65534, 100, 20000, 65535]);
    // 16-bit TIFF, oiliness 0..1.
    let ptif = dir.path().join("oiliness.tif");
    save_l16(&ptif, w, h, vec![65535, 0, 13107, 52428, 1, 2, 3, 4]);
    // 8-bit TIFF, melanin_blend 0..1.
    let ptif8 = dir.path().join("blend.tiff");
    save_l8(&ptif8, w, h, vec![255, 0, 51, 102, 153, 204, 1, 2]);

    let img = read_params(&ParamInputs::Separate([file(&p8), file(&ptif8), file(&p16), file(&ptif)])).unwrap();
    assert_eq!((img.width, img.height), (4, 2));
    let mel = texels(&img.planes[0]);
    assert_eq!(mel[0], 0.0);
    assert_eq!(mel[3], 0.5, "255 in an 8-bit melanin map is the top of its range");
    assert_eq!(mel[1], 0.1);
    assert_eq!(mel[2], mapped(0, 128.0, 255.0));
    assert_eq!(mel[7], mapped(0, 254.0, 255.0));
    let blend = texels(&img.planes[1]);
    assert_eq!(blend[..4], [1.0, 0.0, 0.2, 0.4]);
    let hem = texels(&img.planes[2]);
    assert_eq!(hem[0], 0.0);
    assert_eq!(hem[1], 0.1, "65535 in a 16-bit hemoglobin map is the top of its range");
    assert_eq!(hem[2], mapped(2, 32768.0, 65535.0));
    assert_eq!(hem[3], mapped(2, 1.0, 65535.0));
    let oil = texels(&img.planes[3]);
    assert_eq!(oil[..4], [1.0, 0.0, 0.2, 0.8]);
    assert_eq!(oil[4], mapped(3, 1.0, 65535.0));
}

#[test]
fn mixed_formats_agree_on_row_order() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (3usize, 4usize);
    // Every file encodes its row number: the top row is 0.
    let png = dir.path().join("mel.png");
    save_l8(&png, w as u32, h as u32, (0..w * h).map(|i| (i / w) as u8 * 85).collect());
    let tif = dir.path().join("hem.tif");
    save_l16(&tif, w as u32, h as u32, (0..w * h).map(|i| (i / w) as u16 * 21845).collect());
    let exr_path = dir.path().join("blend.exr");
    let rows: Vec<f32> = (0..w * h).map(|i| (i / w) as f32 / 3.0).collect();
    write_channels_exr(&exr_path, w, h, &[("v", &rows)], ExrOptions::FLOAT_PIZ).unwrap();
    let img =
        read_params(&ParamInputs::Separate([file(&png), file(&exr_path), file(&tif), ParamSource::Constant(0.0)]))
            .unwrap();
    for i in 0..w * h {
        let row = (i / w) as f64 / 3.0;
        let t = img.texel(i);
        assert!((t[0] as f64 - 0.5 * row).abs() < 1e-6, "{i} {t:?}");
        assert!((t[1] as f64 - row).abs() < 1e-6, "{i} {t:?}");
        assert!((t[2] as f64 - 0.1 * row).abs() < 1e-6, "{i} {t:?}");
    }
}

#[test]
fn all_constants_is_an_error() {
    let e = err_text(read_params(&ParamInputs::Separate([
        ParamSource::Constant(0.1),
        ParamSource::Constant(0.5),
        ParamSource::Constant(0.01),
        ParamSource::Constant(0.3),
    ])));
    assert!(e.contains("at least one map"), "{e}");
}

#[test]
fn missing_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.png");
    let e = err_text(read_params(&ParamInputs::Separate([
        ParamSource::Constant(0.1),
        ParamSource::Constant(0.5),
        file(&missing),
        ParamSource::Constant(0.3),
    ])));
    assert!(e.contains(&missing.display().to_string()) && e.contains("hemoglobin map"), "{e}");
    let e = err_text(read_params(&ParamInputs::Multi { path: dir.path().join("gone.exr"), constants: [None; 4] }));
    assert!(e.contains("gone.exr"), "{e}");
    assert!(names_in(dir.path()).is_empty(), "{:?}", names_in(dir.path()));
}

#[test]
fn mismatched_sizes_list_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.png");
    save_l8(&a, 4, 3, vec![0; 12]);
    let b = dir.path().join("b.exr");
    write_channels_exr(&b, 5, 3, &[("Y", &[0.0; 15])], ExrOptions::FLOAT_PIZ).unwrap();
    let c = dir.path().join("c.tif");
    save_l16(&c, 4, 3, vec![0; 12]);
    let e = err_text(read_params(&ParamInputs::Separate([file(&a), ParamSource::Constant(0.5), file(&b), file(&c)])));
    assert!(e.contains("same size"), "{e}");
    assert!(e.contains("a.png is 4x3") && e.contains("b.exr is 5x3") && e.contains("c.tif is 4x3"), "{e}");
    assert!(e.contains("melanin") && e.contains("hemoglobin") && e.contains("oiliness"), "{e}");
    assert_eq!(names_in(dir.path()), ["a.png", "b.exr", "c.tif"]);
}

#[test]
fn rgb_png_and_other_formats_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let rgb = dir.path().join("colour.png");
    image::RgbImage::from_raw(2, 2, vec![0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0]).unwrap().save(&rgb).unwrap();
    let good = dir.path().join("good.png");
    save_l8(&good, 2, 2, vec![0; 4]);
    let e = err_text(read_params(&ParamInputs::Separate([
        file(&good),
        file(&rgb),
        ParamSource::Constant(0.0),
        ParamSource::Constant(0.0),
    ])));
    assert!(e.contains("colour.png") && e.contains("melanin_blend map"), "{e}");
    // RGB is taken only as a grey image (R = G = B): this one differs at texel (1, 0).
    assert!(e.contains("R, G, B") && e.contains("(x, y) = (1, 0)") && e.contains("not grey"), "{e}");

    // Greyscale + alpha is accepted; the alpha is ignored, with a note.
    let la = dir.path().join("la.png");
    image::GrayAlphaImage::from_raw(2, 1, vec![255, 0, 0, 255]).unwrap().save(&la).unwrap();
    let img = read_params(&ParamInputs::Separate([
        file(&la),
        ParamSource::Constant(0.0),
        ParamSource::Constant(0.0),
        ParamSource::Constant(0.0),
    ]))
    .unwrap();
    assert_eq!(texels(&img.planes[0]), [0.5, 0.0]);
    assert!(img.notes.len() == 1 && img.notes[0].contains("alpha"), "{:?}", img.notes);

    // Something that is not an image at all, whatever its extension.
    let text = dir.path().join("notes.png");
    std::fs::write(&text, "not an image").unwrap();
    let e = err_text(read_params(&ParamInputs::Separate([
        file(&text),
        ParamSource::Constant(0.0),
        ParamSource::Constant(0.0),
        ParamSource::Constant(0.0),
    ])));
    assert!(e.contains("notes.png"), "{e}");
    // A PNG named .exr is recognised by content.
    let disguised = dir.path().join("really_png.exr");
    std::fs::copy(&good, &disguised).unwrap();
    let img = read_params(&ParamInputs::Separate([
        file(&disguised),
        ParamSource::Constant(0.0),
        ParamSource::Constant(0.0),
        ParamSource::Constant(0.0),
    ]))
    .unwrap();
    assert_eq!(img.width, 2);
}

#[test]
fn truncated_exr_is_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64, 64);
    let planes: Vec<Vec<f32>> = (0..4).map(|k| plane(w, h, k as f32)).collect();
    let path = dir.path().join("params.exr");
    let channels: Vec<(&str, &[f32])> = PARAM_CHANNELS.iter().zip(&planes).map(|(n, p)| (*n, p.as_slice())).collect();
    for options in all_options() {
        write_channels_exr(&path, w, h, &channels, options).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        for cut in [bytes.len() / 2, bytes.len() - 1, 200, 10] {
            std::fs::write(&path, &bytes[..cut]).unwrap();
            let e = err_text(read_params(&ParamInputs::Multi { path: path.clone(), constants: [None; 4] }));
            assert!(e.contains(&path.display().to_string()), "{options:?} cut at {cut}: {e}");
            let e = err_text(read_exr_channels(&path));
            assert!(e.contains("params.exr"), "{e}");
        }
    }
    assert_eq!(names_in(dir.path()), ["params.exr"]);
}

#[test]
fn dropped_stages_leave_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let v = plane(8, 8, 1.0);
    {
        let a = stage_rgb_exr(&dir.path().join("albedo.exr"), 8, 8, [&v, &v, &v], ExrOptions::FLOAT_PIZ).unwrap();
        let b = stage_bytes(&dir.path().join("albedo.json"), b"{}").unwrap();
        // The temporary files live beside their destination until then.
        assert!(a.temp_path().unwrap().parent() == Some(dir.path()), "{:?} not in {:?}", a.temp_path(), dir.path());
        assert_eq!(names_in(dir.path()).len(), 2);
        assert!(
            names_in(dir.path()).iter().all(|n| n.starts_with('.') && n.ends_with(".tmp")),
            "{:?}",
            names_in(dir.path())
        );
        drop((a, b));
    }
    assert!(names_in(dir.path()).is_empty(), "{:?}", names_in(dir.path()));
}

#[test]
fn committed_stages_appear_together() {
    let dir = tempfile::tempdir().unwrap();
    let v = plane(8, 8, 1.0);
    let staged = vec![
        stage_rgb_exr(&dir.path().join("albedo.exr"), 8, 8, [&v, &v, &v], ExrOptions::FLOAT_PIZ).unwrap(),
        stage_rgb_exr(
            &dir.path().join("radius.exr"),
            8,
            8,
            [&v, &v, &v],
            ExrOptions { precision: Precision::Half, compression: Compression::Piz },
        )
        .unwrap(),
        stage_bytes(&dir.path().join("maps.json"), b"{\"ok\": true}").unwrap(),
    ];
    commit_all(staged).unwrap();
    assert_eq!(names_in(dir.path()), ["albedo.exr", "maps.json", "radius.exr"]);
    assert_eq!(std::fs::read(dir.path().join("maps.json")).unwrap(), b"{\"ok\": true}");
    assert_eq!(read_exr_channels(&dir.path().join("albedo.exr")).unwrap().2[0].1, v);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(dir.path().join("albedo.exr")).unwrap().permissions().mode();
        assert_eq!(mode & 0o600, 0o600, "{mode:o}");
    }
}

#[test]
fn a_failing_later_stage_does_not_clobber_existing_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let albedo = dir.path().join("albedo.exr");
    let old = vec![0.25f32; 16];
    write_rgb_exr(&albedo, 4, 4, [&old, &old, &old], ExrOptions::FLOAT_PIZ).unwrap();
    let old_bytes = std::fs::read(&albedo).unwrap();

    let new = vec![0.75f32; 16];
    let result = (|| {
        let a = stage_rgb_exr(&albedo, 4, 4, [&new, &new, &new], ExrOptions::FLOAT_PIZ)?;
        // The radius planes have the wrong length: staging fails and nothing is committed.
        let r = stage_rgb_exr(&dir.path().join("radius.exr"), 4, 4, [&new, &new, &new[..15]], ExrOptions::FLOAT_PIZ)?;
        commit_all(vec![a, r])
    })();
    let e = result.unwrap_err().to_string();
    assert!(e.contains("radius.exr") && e.contains("expected 4x4 = 16 values; got 15"), "{e}");
    assert_eq!(std::fs::read(&albedo).unwrap(), old_bytes);
    assert_eq!(names_in(dir.path()), ["albedo.exr"]);

    // A commit whose checks fail renames nothing either: here a directory sits where radius.exr should go.
    let a = stage_rgb_exr(&albedo, 4, 4, [&new, &new, &new], ExrOptions::FLOAT_PIZ).unwrap();
    let r = stage_rgb_exr(&dir.path().join("radius.exr"), 4, 4, [&new, &new, &new], ExrOptions::FLOAT_PIZ).unwrap();
    std::fs::create_dir(dir.path().join("radius.exr")).unwrap();
    let e = err_text(commit_all(vec![a, r]));
    assert!(e.contains("radius.exr") && e.contains("directory"), "{e}");
    assert_eq!(std::fs::read(&albedo).unwrap(), old_bytes);
    assert_eq!(names_in(dir.path()), ["albedo.exr", "radius.exr"]);

    // Writing into a directory that does not exist fails before creating anything.
    let nowhere = dir.path().join("missing").join("albedo.exr");
    let e = err_text(write_rgb_exr(&nowhere, 4, 4, [&new, &new, &new], ExrOptions::FLOAT_PIZ));
    assert!(e.contains("missing") && e.contains("directory"), "{e}");
    let e = err_text(write_atomic(&nowhere, b"x"));
    assert!(e.contains("albedo.exr"), "{e}");
    assert_eq!(names_in(dir.path()), ["albedo.exr", "radius.exr"]);
}

#[test]
fn write_atomic_replaces_whole_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("maps.json");
    write_atomic(&path, b"first version, long").unwrap();
    write_atomic(&path, b"second").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"second");
    assert_eq!(names_in(dir.path()), ["maps.json"]);
}

#[test]
fn bad_write_arguments_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x.exr");
    let v = vec![0.0f32; 4];
    let e = err_text(write_channels_exr(&p, 0, 4, &[("Y", &[])], ExrOptions::FLOAT_PIZ));
    assert!(e.contains("0 wide x 4 high"), "{e}");
    let e = err_text(write_channels_exr(&p, 2, 2, &[], ExrOptions::FLOAT_PIZ));
    assert!(e.contains("at least one channel"), "{e}");
    let e = err_text(write_channels_exr(&p, 2, 2, &[("Y", &v), ("Y", &v)], ExrOptions::FLOAT_PIZ));
    assert!(e.contains("twice"), "{e}");
    let e = err_text(write_channels_exr(&p, 2, 2, &[("", &v)], ExrOptions::FLOAT_PIZ));
    assert!(e.contains("channel name"), "{e}");
    assert!(names_in(dir.path()).is_empty(), "{:?}", names_in(dir.path()));
}

/// The compression a written file's header names.
fn compression_on_disk(path: &Path) -> exr::compression::Compression {
    exr::meta::MetaData::read_from_file(path, true).unwrap().headers[0].compression
}

#[test]
fn auto_compression_compresses_where_it_pays_and_not_where_it_does_not() {
    let dir = tempfile::tempdir().unwrap();
    // 64 x 200: 7 PIZ blocks or 200 ZIPS blocks, sampled. A ramp (constant along rows) shrinks under either codec;
    // white noise (a xorshift generator's mantissas, every bit random) cannot shrink by 25 %.
    let (w, h) = (64, 200);
    let smooth: Vec<f32> = (0..w * h).map(|i| 0.2 + 0.001 * (i / w) as f32).collect();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut random_bits = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    // Float: 23 random mantissa bits in [1, 2). Half: random half bit patterns (sign, 10 mantissa bits and 4 of the 5
    // exponent bits random: finite values), exact in f32.
    // Three planes of each, as a repeated plane would compress.
    let float_noise: Vec<Vec<f32>> = (0..3)
        .map(|_| (0..w * h).map(|_| f32::from_bits(0x3f80_0000 | (random_bits() >> 41) as u32)).collect())
        .collect();
    let half_noise: Vec<Vec<f32>> = (0..3)
        .map(|_| (0..w * h).map(|_| half::f16::from_bits((random_bits() >> 48) as u16 & 0xfbff).to_f32()).collect())
        .collect();
    for precision in ALL_PRECISIONS {
        let noise = if precision == Precision::Half { &half_noise } else { &float_noise };
        let options = ExrOptions { precision, compression: Compression::Auto };
        let (candidate, candidate_on_disk) = match precision {
            Precision::Half => (Compression::Zips, exr::compression::Compression::ZIP1),
            Precision::Float => (Compression::Piz, exr::compression::Compression::PIZ),
        };
        assert_eq!(Compression::auto_candidate(precision), candidate, "{precision:?}");
        for (name, planes, expected, on_disk) in [
            ("smooth", [&smooth, &smooth, &smooth], candidate, candidate_on_disk),
            (
                "noise",
                [&noise[0], &noise[1], &noise[2]],
                Compression::None,
                exr::compression::Compression::Uncompressed,
            ),
        ] {
            let path = dir.path().join(format!("{name}.exr"));
            let staged = stage_rgb_exr(&path, w, h, planes.map(Vec::as_slice), options).unwrap();
            assert_eq!(staged.compression(), Some(expected), "{name} {precision:?}");
            staged.commit().unwrap();
            assert_eq!(compression_on_disk(&path), on_disk, "{name} {precision:?}");
            let (_, _, chans) = read_exr_channels(&path).unwrap();
            assert_eq!(chans[2].1, as_stored(planes[0], precision), "{name} {precision:?}");
            // R, stored last
        }
    }
    // A chosen compression is written as asked, whatever the content.
    let path = dir.path().join("forced.exr");
    let staged = stage_rgb_exr(
        &path,
        w,
        h,
        [&float_noise[0], &float_noise[1], &float_noise[2]],
        ExrOptions { precision: Precision::Float, compression: Compression::Rle },
    )
    .unwrap();
    assert_eq!(staged.compression(), Some(Compression::Rle));
    staged.commit().unwrap();
    assert_eq!(compression_on_disk(&path), exr::compression::Compression::RLE);
    // ZIP and ZIPS on noise: blocks that deflate does not shrink are stored raw, and read back exactly.
    for precision in ALL_PRECISIONS {
        let noise = if precision == Precision::Half { &half_noise } else { &float_noise };
        for (compression, on_disk) in [
            (Compression::Zips, exr::compression::Compression::ZIP1),
            (Compression::Zip, exr::compression::Compression::ZIP16),
        ] {
            let path = dir.path().join("forced-zip.exr");
            let planes = [noise[0].as_slice(), noise[1].as_slice(), noise[2].as_slice()];
            write_rgb_exr(&path, w, h, planes, ExrOptions { precision, compression }).unwrap();
            assert_eq!(compression_on_disk(&path), on_disk, "{precision:?} {compression:?}");
            let (_, _, chans) = read_exr_channels(&path).unwrap();
            for (c, plane) in chans.iter().rev().zip(planes) {
                assert_eq!(c.1, as_stored(plane, precision), "{compression:?} {precision:?} {}", c.0);
            }
        }
    }
}

#[test]
fn options_serialise_in_lowercase() {
    let o = ExrOptions { precision: Precision::Float, compression: Compression::Zips };
    let s = serde_json::to_string(&o).unwrap();
    assert_eq!(s, r#"{"precision":"float","compression":"zips"}"#);
    assert_eq!(serde_json::from_str::<ExrOptions>(&s).unwrap(), o);
    assert_eq!(ExrOptions::default(), ExrOptions { precision: Precision::Half, compression: Compression::Auto });
    assert_eq!(serde_json::to_string(&Compression::None).unwrap(), r#""none""#);
}

#[test]
fn param_image_helpers() {
    let img = ParamImage {
        width: 2,
        height: 1,
        planes: [
            Plane::Texels(vec![0.1, 0.2]),
            Plane::Constant(0.5),
            Plane::Constant(0.01),
            Plane::Texels(vec![0.3, 0.4]),
        ],
        extended: default_extended(),
        notes: Vec::new(),
    };
    assert_eq!(img.texel_count(), 2);
    assert_eq!(img.texel(1), [0.2, 0.5, 0.01, 0.4]);
    assert!(img.planes[1].is_constant(), "{:?}", img.planes[1]);
}

/// The bytes reader (what the fuzz target drives) gives what the file reader gives, for the four-channel EXR and for
/// one-parameter EXR, PNG and TIFF files; the other planes are NaN constants; errors name the label; a bad parameter
/// index is an error.
#[test]
fn bytes_reader_equals_file_reader() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (5, 3);
    let multi = dir.path().join("multi.exr");
    let planes: Vec<Vec<f32>> = (0..4).map(|p| plane(w, h, p as f32)).collect();
    let channels: Vec<(&str, &[f32])> = PARAM_CHANNELS.iter().zip(&planes).map(|(n, v)| (*n, v.as_slice())).collect();
    write_channels_exr(&multi, w, h, &channels, ExrOptions::FLOAT_PIZ).unwrap();
    let from_file = read_params(&ParamInputs::Multi { path: multi.clone(), constants: [None; 4] }).unwrap();
    let from_bytes = read_params_from_bytes(&std::fs::read(&multi).unwrap(), "multi", None).unwrap();
    assert_eq!(from_bytes, from_file);

    let single = dir.path().join("single.exr");
    write_channels_exr(&single, w, h, &[("Y", &planes[2])], ExrOptions::FLOAT_PIZ).unwrap();
    let png = dir.path().join("m.png");
    save_l8(&png, w as u32, h as u32, (0..w * h).map(|i| (i * 17) as u8).collect());
    let tif = dir.path().join("m.tif");
    save_l16(&tif, w as u32, h as u32, (0..w * h).map(|i| (i * 4000) as u16).collect());
    for (p, path) in [(2, &single), (0, &png), (3, &tif)] {
        let mut sources: [ParamSource; 4] = std::array::from_fn(|_| ParamSource::Constant(0.0));
        sources[p] = file(path);
        let from_file = read_params(&ParamInputs::Separate(sources)).unwrap();
        let from_bytes = read_params_from_bytes(&std::fs::read(path).unwrap(), "m", Some(p)).unwrap();
        assert_eq!((from_bytes.width, from_bytes.height), (w, h), "{}", path.display());
        assert_eq!(from_bytes.planes[p], from_file.planes[p], "{}", path.display());
        for (k, plane) in from_bytes.planes.iter().enumerate().filter(|(k, _)| *k != p) {
            assert!(matches!(plane, Plane::Constant(v) if v.is_nan()), "plane {k}: {plane:?}");
        }
    }

    let e = err_text(read_params_from_bytes(b"not an image", "packed image", Some(0)));
    assert!(e.contains("packed image") && e.contains("EXR, PNG, TIFF or JPEG"), "{e}");
    let e = err_text(read_params_from_bytes(&std::fs::read(&multi).unwrap(), "multi", Some(4)));
    assert!(e.contains("parameter index") && e.contains("got 4"), "{e}");
}

/// A chunk whose declared size runs past the end of the file is an error naming the chunk before anything is read:
/// the exr crate would first allocate and zero-fill that size (up to the largest block the header allows: here
/// 64 MiB, for a file of a few hundred bytes; a fuzzed 690-byte file made it touch 1 GB). The file is one of our own,
/// with the data window widened to 2^24 texels and the chunk's size field patched (OpenEXR's layout: after the
/// header one u64 offset per chunk; a scan-line chunk starts `y: i32, size: i32`).
#[test]
fn chunk_sizes_past_the_end_are_refused_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.exr");
    let options = ExrOptions { precision: Precision::Float, compression: Compression::None };
    write_channels_exr(&path, 4, 1, &[("Y", &[0.1, 0.2, 0.3, 0.4])], options).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    let window = bytes.windows(17).position(|w| w == b"dataWindow\0box2i\0").unwrap() + 17 + 4;
    bytes[window + 8..window + 12].copy_from_slice(&((1i32 << 24) - 1).to_le_bytes()); // xmax
    let header_end = bytes.len() - 8 - (8 + 16); // one offset, one chunk of 4 f32
    let chunk = u64::from_le_bytes(bytes[header_end..header_end + 8].try_into().unwrap()) as usize;
    assert_eq!(chunk, header_end + 8, "the chunk follows the offset table");
    bytes[chunk + 4..chunk + 8].copy_from_slice(&(1i32 << 26).to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let mut sources: [ParamSource; 4] = std::array::from_fn(|_| ParamSource::Constant(0.0));
    sources[0] = file(&path);
    let e = err_text(read_params(&ParamInputs::Separate(sources)));
    assert!(e.contains("m.exr") && e.contains("chunk 0") && e.contains("claims 67108864 bytes"), "{e}");
    let e = err_text(read_params_from_bytes(&bytes, "packed", Some(0)));
    assert!(e.contains("packed") && e.contains("claims 67108864 bytes"), "{e}");
    // The unpatched size with the wide window is still a clear error (too few texels), not the chunk check's.
    bytes[chunk + 4..chunk + 8].copy_from_slice(&16i32.to_le_bytes());
    let e = err_text(read_params_from_bytes(&bytes, "packed", Some(0)));
    assert!(e.contains("packed") && !e.contains("claims"), "{e}");
}

#[test]
fn io_errors_keep_the_operating_systems_error_as_their_source() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.exr");
    let err = read_params(&ParamInputs::Multi { path: missing.clone(), constants: [None; 4] }).unwrap_err();
    assert!(err.to_string().contains("missing.exr"), "{err}");
    let source = std::error::Error::source(&err).expect("an I/O error keeps its source");
    let source = source.downcast_ref::<spectral_skin::error::IoSource>().expect("the source is the OS error");
    assert_eq!(source.error().kind(), std::io::ErrorKind::NotFound);
    // A failure the core detects itself (no OS error) has no source.
    let err = stage_bytes(&dir.path().join("absent").join("out.json"), b"{}").unwrap_err();
    assert!(err.to_string().contains("expected an existing directory"), "{err}");
    assert!(std::error::Error::source(&err).is_none(), "{err}");
}

/// A dangling symbolic link as the output folder (or one of its parents) is named as such before anything is written
/// (issue 38 item 5: creating it failed with the operating system's "File exists").
#[cfg(unix)]
#[test]
fn a_dangling_symlink_as_the_output_folder_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("out");
    std::os::unix::fs::symlink(dir.path().join("gone"), &link).unwrap();
    for folder in [link.clone(), link.join("maps")] {
        let e = spectral_skin::maps::io::create_output_dir(&folder).expect_err("a dangling link").to_string();
        assert!(e.contains("symbolic link") && e.contains("gone") && !e.contains("File exists"), "{e}");
    }
}
