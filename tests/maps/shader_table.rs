//! The shader table (src/maps/shader_table.rs): its layout reproduces the material table's trilinear lookup when
//! sampled as Blender's Image Texture node samples it, its error against direct evaluation stays within the bound
//! docs/shader-table.md reports, and its files read back as written.

use spectral_skin::evaluate::Prepared;
use spectral_skin::fit::SubsurfaceMethod;
use spectral_skin::maps::io::{read_exr_channels, ExrOptions};
use spectral_skin::maps::lut::{MaterialTable, TableResolution};
use spectral_skin::maps::shader_table::{
    measure_shader_error, ShaderTable, ShaderTableMeta, DEFAULT_SHADER_TABLE_RESOLUTION, SHADER_BASE_COLOR_FILE,
    SHADER_RADIUS_FILE, SHADER_SIDECAR_FILE, SHADER_TABLE_EXR,
};
use spectral_skin::{Outputs, Request};

fn prepared() -> Prepared {
    Prepared::new(&Request::new(Outputs::material())).unwrap()
}

/// A small uneven grid: every axis has a different node count, so a swapped axis or a wrong stride shows.
const SMALL: TableResolution = TableResolution { melanin: 6, melanin_blend: 4, hemoglobin: 5 };

/// Deterministic points over the whole domain and slightly beyond (clamped by both), with the domain's corners and
/// edges, where a guard column or a slice border would show.
fn points() -> Vec<[f32; 3]> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut out: Vec<[f32; 3]> = (0..2000)
        .map(|_| [(next() * 0.52 - 0.01) as f32, (next() * 1.04 - 0.02) as f32, (next() * 0.104 - 0.002) as f32])
        .collect();
    for m in [0.0, 0.5] {
        for b in [0.0, 1.0 / 3.0, 0.5, 2.0 / 3.0, 1.0] {
            for h in [0.0, 0.1] {
                out.push([m, b, h]);
            }
        }
    }
    out
}

#[test]
fn sampling_the_images_as_blender_does_reproduces_the_trilinear_table() {
    let prepared = prepared();
    for method in [SubsurfaceMethod::Burley, SubsurfaceMethod::RandomWalk] {
        let table = MaterialTable::build(&prepared, method, SMALL).unwrap();
        let shader = ShaderTable::from_table(&table, &prepared).unwrap();
        let m = shader.meta();
        assert_eq!((m.width, m.height, m.slice_width), (4 * 8, 5, 8), "{method:?}");
        assert_eq!(shader.texel_bytes(), 2 * 3 * 32 * 5 * 4, "{method:?}");
        let mut worst = 0.0f32;
        for [c_m, beta, c_h] in points() {
            let (bc, rad) = shader.sample(c_m, beta, c_h);
            let (bc_ref, rad_ref) = table.lookup_method(c_m, beta, c_h);
            for c in 0..3 {
                worst = worst.max(((bc[c] - bc_ref[c]) / bc_ref[c]).abs());
                worst = worst.max(((rad[c] - rad_ref[c]) / rad_ref[c]).abs());
            }
        }
        // f32 round-off of the texture coordinates and of powf against the table's f64 cube root: well below 1e-5;
        // a wrong layout (axis, row order, slice offset, guard) is off by whole percent.
        assert!(worst < 1e-5, "{method:?}: worst relative difference {worst:e}");
    }
}

#[test]
fn guard_columns_copy_the_outer_nodes_and_rows_run_bottom_up() {
    let prepared = prepared();
    let table = MaterialTable::build(&prepared, SubsurfaceMethod::Burley, SMALL).unwrap();
    let shader = ShaderTable::from_table(&table, &prepared).unwrap();
    let (w, h, sw) = (shader.meta().width, shader.meta().height, shader.meta().slice_width);
    let bc = shader.base_color_log();
    for j in 0..SMALL.melanin_blend {
        for k in 0..SMALL.hemoglobin {
            let row = (h - 1 - k) * w; // node k counted from the bottom; row 0 of the plane is the top
            let (first, _) = table.node_log_method(0, j, k);
            let (last, _) = table.node_log_method(SMALL.melanin - 1, j, k);
            for c in 0..3 {
                assert_eq!(bc[c][row + j * sw], first[c], "blend node {j}, hemoglobin node {k}, channel {c}");
                assert_eq!(bc[c][row + j * sw + 1], first[c], "blend node {j}, hemoglobin node {k}, channel {c}");
                assert_eq!(bc[c][row + j * sw + sw - 2], last[c], "blend node {j}, hemoglobin node {k}, channel {c}");
                assert_eq!(bc[c][row + j * sw + sw - 1], last[c], "blend node {j}, hemoglobin node {k}, channel {c}");
            }
        }
    }
}

/// The default's error over the whole domain against direct evaluation, within the figures docs/shader-table.md
/// reports for it (0.63 % radius, 0.41 % Base Color for Burley), with a margin for the few sample points used here.
#[test]
fn default_table_error_against_direct_evaluation_is_within_one_percent() {
    let prepared = prepared();
    let shader = ShaderTable::build(&prepared, SubsurfaceMethod::Burley, DEFAULT_SHADER_TABLE_RESOLUTION).unwrap();
    let e = measure_shader_error(&shader, &prepared, 256).unwrap();
    assert!(e.max_base_color_relative < 0.01, "{e:?}");
    assert!(e.max_radius_relative < 0.01, "{e:?}");
    // And it is a real measurement: interpolation between nodes is not exact.
    assert!(e.max_base_color_relative > 1e-5 && e.max_radius_relative > 1e-5, "{e:?}");
}

#[test]
fn files_read_back_as_written_with_their_metadata() {
    let prepared = prepared();
    let table = MaterialTable::build(&prepared, SubsurfaceMethod::Burley, SMALL).unwrap();
    let shader = ShaderTable::from_table(&table, &prepared).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let paths = shader.write(dir.path(), Some("face"), SHADER_TABLE_EXR).unwrap();
    assert_eq!(paths.len(), 3);
    for (file, planes) in [(SHADER_BASE_COLOR_FILE, shader.base_color_log()), (SHADER_RADIUS_FILE, shader.radius_log())]
    {
        let (w, h, channels) = read_exr_channels(&dir.path().join(format!("face_{file}"))).unwrap();
        assert_eq!((w, h), (shader.meta().width, shader.meta().height), "{file}");
        for (name, plane) in ["R", "G", "B"].iter().zip(planes) {
            let read = &channels.iter().find(|(n, _)| n == name).unwrap().1;
            assert_eq!(read, plane, "{file} {name}");
        }
    }
    let text = std::fs::read_to_string(dir.path().join(format!("face_{SHADER_SIDECAR_FILE}"))).unwrap();
    let meta: ShaderTableMeta = serde_json::from_str(&text).unwrap();
    assert_eq!(&meta, shader.meta());
    let parts = ShaderTable::from_parts(meta, shader.base_color_log().clone(), shader.radius_log().clone()).unwrap();
    assert_eq!(parts.sample(0.1, 0.5, 0.02), shader.sample(0.1, 0.5, 0.02));
    let written = shader.write(dir.path(), Some("a/b"), ExrOptions::default());
    assert!(written.is_err(), "prefix \"a/b\": {written:?}");
}
