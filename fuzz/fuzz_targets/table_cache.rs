//! The cached-table reader (`maps::lut::MaterialTable::from_cache_bytes`, the code the cache runs on its files).
//! The first bytes pick the expected method and resolution (2-5 nodes per axis) and a mode: the rest taken as the
//! whole file; as a body behind the magic line and its correct checksum (so the fuzzer reaches the size and value
//! checks); or as node values behind a correct header and checksum, cut or zero-padded to the expected length.
//! Asserts: a table it returns has the expected resolution and method and interpolates to finite positive values at
//! the nodes, cell centres and points decoded from the input; nothing panics.

#![no_main]

mod common;

use common::Bytes;
use libfuzzer_sys::fuzz_target;
use spectral_skin::fit::SubsurfaceMethod;
use spectral_skin::maps::lut::{MaterialTable, TableResolution, CACHE_MAGIC};

/// 64-bit FNV-1a (Fowler, Noll & Vo: offset basis 0xcbf29ce484222325, prime 0x100000001b3), written here from its
/// definition, not taken from the code under test.
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// The request key the fuzzed files carry (the reader compares it with the one it is asked for).
const KEY: &str = "fuzzed request";

/// A file around `body`: the magic, the checksum, the key's length and the key, then `body`.
fn wrap(body: &[u8]) -> Vec<u8> {
    let mut keyed = (KEY.len() as u32).to_le_bytes().to_vec();
    keyed.extend_from_slice(KEY.as_bytes());
    keyed.extend_from_slice(body);
    let mut file = CACHE_MAGIC.to_vec();
    file.extend_from_slice(&fnv1a(&keyed).to_le_bytes());
    file.extend_from_slice(&keyed);
    file
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let mode = b.byte() % 3;
    let method = SubsurfaceMethod::ALL[usize::from(b.byte() % 4)];
    let mut axis = || 2 + usize::from(b.byte() % 4);
    let resolution = TableResolution { melanin: axis(), melanin_blend: axis(), hemoglobin: axis() };
    let probes: Vec<[f32; 3]> = (0..b.byte() % 8).map(|_| [b.unit(), b.unit(), b.unit()].map(|u| u as f32)).collect();
    let rest = b.rest();
    let file = match mode {
        0 => rest.to_vec(),
        1 => wrap(rest),
        _ => {
            let mut body = Vec::new();
            for n in [resolution.melanin, resolution.melanin_blend, resolution.hemoglobin] {
                body.extend_from_slice(&(n as u32).to_le_bytes());
            }
            let values = resolution.node_count() * 9 * 4;
            body.extend_from_slice(&rest[..rest.len().min(values)]);
            body.resize(12 + values, 0);
            wrap(&body)
        }
    };
    let Some(table) = MaterialTable::from_cache_bytes(&file, KEY, method, resolution) else { return };
    assert_eq!(table.resolution(), resolution);
    assert_eq!(table.method(), method);
    // Nodes and cell centres of the warped axes (the domain is [0, 0.5] x [0, 1] x [0, 0.1], cube-root warped for
    // the two concentrations), and the decoded points, scaled onto the domain and a little beyond.
    let mut points = Vec::new();
    for i in 0..=2 * (resolution.melanin - 1) {
        let u = i as f32 / (2 * (resolution.melanin - 1)) as f32;
        points.push([0.5 * u.powi(3), u, 0.1 * u.powi(3)]);
    }
    points.extend(probes.iter().map(|p| [0.6 * p[0] - 0.05, 1.2 * p[1] - 0.1, 0.12 * p[2] - 0.01]));
    for [m, b, h] in points {
        let t = table.lookup(m, b, h);
        for v in t.albedo.iter().chain(&t.base_color).chain(&t.radius_mm) {
            assert!(v.is_finite() && *v > 0.0, "lookup({m}, {b}, {h}) = {t:?}");
        }
        let (c, r) = table.lookup_method(m, b, h);
        assert!(c.iter().chain(&r).all(|v| v.is_finite() && *v > 0.0), "lookup_method({m}, {b}, {h})");
    }
});
