//! Measured skin colours: the Xiao et al. 2016 in-vivo reflectance spectra (data/xiao2016_skin_reflectance_400_700nm
//! .csv, 400-700 nm every 10 nm) as linear RGB under D65 with the CIE 1931 observer, by the core's colour integration
//! (the reflectance is held flat outside 400-700 nm, where the data stop).

use spectral_skin::color::{spectral_rgb_weights, spectrum_to_rgb, WavelengthGrid, WorkingSpace};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/xiao2016_skin_reflectance_400_700nm.csv");

/// Every `every`th spectrum of the data file and its wavelengths (from the header `index,R400,...`).
pub fn xiao_spectra(every: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(DATA).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let wl = lines.next().unwrap().split(',').skip(1).map(|h| h[1..].parse().unwrap()).collect();
    let spectra = lines.step_by(every).map(|l| l.split(',').skip(1).map(|v| v.parse().unwrap()).collect()).collect();
    (wl, spectra)
}

/// `count` measured skin colours spread evenly over the data file (its eight ethnic groups), linear RGB in `space`.
pub fn measured_skin_colours(count: usize, space: WorkingSpace) -> Vec<[f64; 3]> {
    let (wl, all) = xiao_spectra(1);
    let weights = spectral_rgb_weights(&WavelengthGrid { wavelengths_nm: wl }, space);
    let every = all.len() / count;
    all.iter().step_by(every).take(count).map(|s| spectrum_to_rgb(s, &weights)).collect()
}
