//! `run_maps` fills and writes its maps a block of rows at a time (`STREAM_ROWS`), reading a UDIM set a tile at a
//! time: its files must be the very bytes that the whole-image path (`compute_maps`, then `stage_map_files`, which
//! Python's `write_maps` uses) writes, in every encoding and for every strategy, and a tile set must still be decided
//! and computed as one texture (each tile's maps the rows of the stacked texture's).

use std::path::Path;

use spectral_skin::maps::io::{
    check_texel_count, default_extended, read_exr_channels, read_params, write_channels_exr, Compression, ExrOptions,
    ParamImage, ParamInputs, Plane, Precision, PARAM_CHANNELS, STREAM_ROWS,
};
use spectral_skin::maps::lut::TableResolution;
use spectral_skin::maps::pipeline::{
    check_planes, stage_map_files, MapFiles, Strategy, ALBEDO_FILE, MAP_KINDS, RADIUS_FILE, SPECULAR_FILE,
};
use spectral_skin::maps::{compute_maps, run_maps, MapSettings, StrategyChoice};

fn settings(strategy: StrategyChoice) -> MapSettings {
    MapSettings {
        strategy,
        // A small table keeps the test quick; the streaming does not depend on its size.
        table: TableResolution { melanin: 5, melanin_blend: 3, hemoglobin: 4 },
        table_check_samples: 4,
        ..MapSettings::default()
    }
}

/// A `width` x `height` map whose four parameters vary smoothly (every texel its own tuple: the table strategy).
fn smooth(width: usize, height: usize, phase: f32) -> ParamImage {
    let plane = |f: &dyn Fn(f32, f32) -> f32| {
        Plane::Texels(
            (0..width * height)
                .map(|i| f((i % width) as f32 / width as f32, (i / width) as f32 / height as f32))
                .collect(),
        )
    };
    ParamImage {
        width,
        height,
        planes: [
            plane(&|x, y| 0.01 + 0.3 * (x * y + phase).fract()),
            plane(&|x, _| 0.2 + 0.6 * x),
            plane(&|_, y| 0.005 + 0.08 * y),
            plane(&|x, y| 0.5 + 0.5 * (7.0 * x + 3.0 * y + phase).sin()),
        ],
        extended: default_extended(),
        notes: Vec::new(),
    }
}

/// A map whose planes hold one value each, as texels.
fn uniform(width: usize, height: usize, values: [f32; 4]) -> ParamImage {
    ParamImage {
        width,
        height,
        planes: values.map(|v| Plane::Texels(vec![v; width * height])),
        extended: default_extended(),
        notes: Vec::new(),
    }
}

fn texels(plane: &Plane) -> &[f32] {
    match plane {
        Plane::Texels(values) => values,
        Plane::Constant(_) => panic!("the test writes texel planes"),
    }
}

/// Write `image`'s four planes as a float EXR (read back exactly).
fn write_params(path: &Path, image: &ParamImage) {
    let channels: Vec<(&str, &[f32])> = PARAM_CHANNELS.iter().copied().zip(image.planes.iter().map(texels)).collect();
    write_channels_exr(path, image.width, image.height, &channels, ExrOptions::FLOAT_PIZ).unwrap();
}

fn multi(path: &Path) -> ParamInputs {
    ParamInputs::Multi { path: path.to_path_buf(), constants: [None; 4] }
}

/// The whole-image path: read, check, compute every row at once, stage the planes and commit them.
fn write_whole(inputs: &ParamInputs, out: &Path, settings: &MapSettings, exr: ExrOptions) {
    let mut image = read_params(inputs).unwrap();
    check_planes(&mut image, false).unwrap();
    let r = compute_maps(&image, settings, None).unwrap();
    let surface = r.specular.as_ref().map(|s| s.maps()).unwrap_or_default();
    let files = MapFiles {
        width: r.width,
        height: r.height,
        base_color: r.base_color.as_ref(),
        radius_mm: r.radius_mm.as_ref(),
        surface,
    };
    for staged in stage_map_files(out, None, None, &files, exr).unwrap() {
        staged.commit().unwrap();
    }
}

#[test]
fn streamed_maps_are_the_bytes_of_the_whole_image_write() {
    let dir = tempfile::tempdir().unwrap();
    // More rows than two blocks, and not a multiple of any compression's block height.
    let height = 2 * STREAM_ROWS + 37;
    let params = dir.path().join("params.exr");
    write_params(&params, &smooth(23, height, 0.0));
    let exact = dir.path().join("exact.exr");
    write_params(&exact, &smooth(5, 3, 0.3));
    let half = |compression| ExrOptions { precision: Precision::Half, compression };
    let float = |compression| ExrOptions { precision: Precision::Float, compression };
    let cases = [
        (&params, StrategyChoice::Auto, ExrOptions::default()),
        (&params, StrategyChoice::Auto, float(Compression::Auto)),
        (&params, StrategyChoice::Auto, half(Compression::Piz)),
        (&params, StrategyChoice::Auto, float(Compression::Zip)),
        (&params, StrategyChoice::Auto, half(Compression::Rle)),
        (&params, StrategyChoice::Auto, float(Compression::None)),
        (&exact, StrategyChoice::Exact, ExrOptions::default()),
    ];
    for (k, (path, strategy, exr)) in cases.into_iter().enumerate() {
        let (streamed, whole) = (dir.path().join(format!("s{k}")), dir.path().join(format!("w{k}")));
        let settings = settings(strategy);
        let report = run_maps(&multi(path), &streamed, &settings, exr, None).unwrap();
        write_whole(&multi(path), &whole, &settings, exr);
        let mut compared = 0;
        for kind in MAP_KINDS {
            let (a, b) = (streamed.join(kind.file), whole.join(kind.file));
            assert_eq!(a.exists(), b.exists(), "case {k}: {} written by one path only", kind.file);
            if a.exists() {
                let (a, b) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
                assert!(a == b, "case {k} ({strategy:?}, {exr:?}): {} differs", kind.file);
                compared += 1;
            }
        }
        // Base Color, radius and the varying oiliness's surface maps (the default measured surface: Specular IOR
        // Level, Coat Weight, Coat Roughness).
        assert_eq!(compared, 5, "case {k}: {:?}", report.strategy);
        let expected_table = strategy == StrategyChoice::Auto;
        assert_eq!(
            matches!(report.strategy, Strategy::Table { .. }),
            expected_table,
            "case {k}: {:?}",
            report.strategy
        );
    }
}

#[test]
fn a_tile_set_is_decided_and_computed_as_one_texture() {
    let dir = tempfile::tempdir().unwrap();
    let width = 19;
    // A smooth tile taller than a block, a tile of one value everywhere (alone: the constant strategy), a short one.
    let tiles = [
        (1001u32, smooth(width, STREAM_ROWS + 5, 0.1)),
        (1002, uniform(width, 7, [0.07, 0.4, 0.03, 0.25])),
        (1011, smooth(width, 3, 0.6)),
    ];
    for (tile, image) in &tiles {
        write_params(&dir.path().join(format!("params.{tile}.exr")), image);
    }
    let exr = ExrOptions::FLOAT_PIZ;
    let settings = settings(StrategyChoice::Auto);
    let out = dir.path().join("out");
    let report = run_maps(&multi(&dir.path().join("params.<UDIM>.exr")), &out, &settings, exr, None).unwrap();
    assert_eq!(report.tiles, vec![1001, 1002, 1011]);
    let height: usize = tiles.iter().map(|(_, i)| i.height).sum();
    assert_eq!((report.width, report.height), (width, height));
    assert!(matches!(report.strategy, Strategy::Table { .. }), "{:?}", report.strategy);

    // The stacked texture, computed whole.
    check_texel_count("test", width, height).unwrap();
    let stacked = ParamImage {
        width,
        height,
        planes: std::array::from_fn(|p| {
            Plane::Texels(tiles.iter().flat_map(|(_, i)| texels(&i.planes[p]).iter().copied()).collect())
        }),
        extended: default_extended(),
        notes: Vec::new(),
    };
    let whole = compute_maps(&stacked, &settings, None).unwrap();
    let specular = match whole.specular.as_ref().unwrap().maps().first() {
        Some((_, plane)) => plane.to_vec(),
        None => panic!("the oiliness varies: a specular map"),
    };
    let expected = [
        (ALBEDO_FILE, whole.base_color.as_ref().unwrap().to_vec()),
        (RADIUS_FILE, whole.radius_mm.as_ref().unwrap().to_vec()),
        (SPECULAR_FILE, vec![specular]),
    ];
    let mut first_row = 0;
    for (tile, image) in &tiles {
        let rows = first_row * width..(first_row + image.height) * width;
        for (file, planes) in &expected {
            let name = file.replace(".exr", &format!(".{tile}.exr"));
            let (w, h, channels) = read_exr_channels(&out.join(&name)).unwrap();
            assert_eq!((w, h), (width, image.height), "{name}");
            // Channels are stored sorted by name: B, G, R (or Y alone).
            let by_name = |n: &str| &channels.iter().find(|(c, _)| c == n).unwrap().1;
            let read: Vec<&Vec<f32>> =
                if planes.len() == 3 { vec![by_name("R"), by_name("G"), by_name("B")] } else { vec![by_name("Y")] };
            for (c, plane) in planes.iter().enumerate() {
                assert!(read[c][..] == plane[rows.clone()], "{name} channel {c}: not the stacked texture's rows");
            }
        }
        first_row += image.height;
    }
}

#[test]
fn a_tile_set_with_a_bad_tile_writes_nothing_and_names_the_tile() {
    let dir = tempfile::tempdir().unwrap();
    write_params(&dir.path().join("params.1001.exr"), &smooth(8, 4, 0.0));
    write_params(&dir.path().join("params.1002.exr"), &uniform(8, 4, [0.9, 0.4, 0.03, 0.25]));
    let out = dir.path().join("out");
    let err = run_maps(
        &multi(&dir.path().join("params.<UDIM>.exr")),
        &out,
        &settings(StrategyChoice::Auto),
        ExrOptions::default(),
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("tile 1002"), "{err}");
    assert!(!out.exists(), "a failed run leaves no output folder");
}
