//! The parameter-map reader (`maps::io::read_params_from_bytes`, the code `read_params` runs on files) on arbitrary
//! bytes: the first byte picks the four-channel parameter EXR or a one-parameter file (EXR, PNG, TIFF or JPEG) for
//! one of the four parameters. Asserts: Ok gives an image of 1 to MAX_TEXELS texels with every plane read of that size
//! (the others NaN constants), and a PNG/TIFF/JPEG's values inside the parameter's range; an error has a message;
//! nothing panics or aborts.

#![no_main]

use libfuzzer_sys::fuzz_target;
use spectral_skin::maps::io::{read_params_from_bytes, Plane, MAX_TEXELS, PARAM_RANGES};

/// The OpenEXR magic number (OpenEXR file layout, "Magic Number").
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// The reader runs every third-party decoder under `catch_unwind` (`maps::io::guard`; exr also catches its block
/// decompressors' panics) and reports a decoder's panic on a damaged file as an error. libfuzzer-sys's hook aborts at
/// any panic, caught or not; this one lets a panic raised inside a dependency's source (a registry path) unwind to
/// that guard. A panic in the project's own code still aborts here, and one that escapes the reader aborts in
/// libfuzzer-sys's wrapper. (Found: exr 1.74's B44 decompressor subtracts with overflow on a damaged block, seed
/// `b44_overflow.exr.seed` of this target.)
fn let_guarded_dependency_panics_unwind() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let abort = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let file = info.location().map(|l| l.file().replace('\\', "/")).unwrap_or_default();
            if !file.contains("/registry/src/") {
                abort(info);
            }
        }));
    });
}

fuzz_target!(|data: &[u8]| {
    let_guarded_dependency_panics_unwind();
    let Some((&selector, bytes)) = data.split_first() else { return };
    let parameter = match selector % 5 {
        4 => None,
        p => Some(usize::from(p)),
    };
    match read_params_from_bytes(bytes, "fuzz input", parameter) {
        Ok(image) => {
            let texels = image.width * image.height;
            assert!((1..=MAX_TEXELS).contains(&texels), "{}x{}", image.width, image.height);
            for (p, plane) in image.planes.iter().enumerate() {
                match plane {
                    Plane::Texels(values) => {
                        assert!(parameter.is_none() || parameter == Some(p), "plane {p} read");
                        assert_eq!(values.len(), texels);
                        if !bytes.starts_with(&EXR_MAGIC) {
                            let (lo, hi) = (PARAM_RANGES[p].0 as f32, PARAM_RANGES[p].1 as f32);
                            assert!(values.iter().all(|v| (lo..=hi).contains(v)), "integer image out of range");
                        }
                    }
                    Plane::Constant(v) => assert!(parameter.is_some_and(|q| q != p) && v.is_nan(), "plane {p}"),
                }
            }
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
});
