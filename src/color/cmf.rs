//! CIE 1931 2-degree colour-matching functions and illuminant D65, 1 nm tables from `data/` (docs/model.md, section
//! Data files).

use std::sync::OnceLock;

use crate::table::SpectralTable;

const CMF_CSV: &str = include_str!("../../data/cie1931_2deg_cmf.csv");
const D65_CSV: &str = include_str!("../../data/cie_d65.csv");

/// xbar, ybar, zbar (columns 0, 1, 2), 360-830 nm at 1 nm.
pub fn cie1931_2deg() -> &'static SpectralTable {
    static T: OnceLock<SpectralTable> = OnceLock::new();
    T.get_or_init(|| SpectralTable::parse(CMF_CSV))
}

/// Relative spectral power of D65 (100 at 560 nm), 300-830 nm at 1 nm.
pub fn illuminant_d65() -> &'static SpectralTable {
    static T: OnceLock<SpectralTable> = OnceLock::new();
    T.get_or_init(|| SpectralTable::parse(D65_CSV))
}
