//! `diffusion::layered_reflectance` on 1-4 layers and 0-8 radii decoded from the input, inside and far outside the
//! accepted ranges. Asserts: Ok gives a finite total in [0, 1] and one finite profile value >= 0 per radius; an
//! error has a message; nothing panics.

#![no_main]

mod common;

use common::Bytes;
use libfuzzer_sys::fuzz_target;
use spectral_skin::layer::Layer;
use spectral_skin::reflectance::layered_reflectance;

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let count = 1 + b.byte() % 4;
    let layers: Vec<Layer> = (0..count)
        .map(|i| {
            let semi_infinite = i + 1 == count && b.byte() % 2 == 0;
            Layer {
                thickness_mm: if semi_infinite { f64::INFINITY } else { b.log_value(-14.0, 8.0) },
                sigma_a_per_mm: b.log_value(-14.0, 8.0),
                sigma_s_reduced_per_mm: b.log_value(-14.0, 8.0),
                ior: b.linear(0.5, 4.0),
            }
        })
        .collect();
    let radii: Vec<f64> = (0..b.byte() % 9).map(|_| b.log_value(-8.0, 7.0)).collect();
    match layered_reflectance(&layers, &radii) {
        Ok((total, profile)) => {
            assert!(total.is_finite() && (0.0..=1.0).contains(&total), "total {total} for {layers:?}");
            assert_eq!(profile.len(), radii.len());
            for (r, p) in radii.iter().zip(&profile) {
                assert!(p.is_finite() && *p >= 0.0, "R({r} mm) = {p} for {layers:?}");
            }
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
});
