//! The individual typology angle (ITA°) of a skin colour and its classes: the dermatological scale of constitutive
//! skin colour by CIELAB lightness and yellowness, ITA = atan((L* − 50) / b*) in degrees (Chardon, Cretois &
//! Hourseau, Int. J. Cosmet. Sci. 13:191, 1991: the classes very light to brown; Del Bino et al., Pigment Cell Res.
//! 19:606, 2006: "dark" below −30°, splitting Chardon's brown).

/// ITA° of a CIELAB colour: atan2(L* − 50, b*) in degrees, so a colour with b* ≤ 0 still gets an angle (±90° at
/// b* = 0, the sign of L* − 50).
pub fn ita_degrees(lab: [f64; 3]) -> f64 {
    (lab[0] - 50.0).atan2(lab[2]).to_degrees()
}

/// One class of the ITA° scale: `name` (lower case, hyphenated: a preset's name), its label, and its half-open
/// range of angles [min_deg, max_deg).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ItaClass {
    pub name: &'static str,
    pub label: &'static str,
    pub min_deg: f64,
    pub max_deg: f64,
}

/// The six classes, lightest first (Chardon et al. 1991; Del Bino et al. 2006). They cover every angle.
pub const ITA_CLASSES: [ItaClass; 6] = [
    ItaClass { name: "very-light", label: "very light (> 55°)", min_deg: 55.0, max_deg: f64::INFINITY },
    ItaClass { name: "light", label: "light (41–55°)", min_deg: 41.0, max_deg: 55.0 },
    ItaClass { name: "intermediate", label: "intermediate (28–41°)", min_deg: 28.0, max_deg: 41.0 },
    ItaClass { name: "tan", label: "tan (10–28°)", min_deg: 10.0, max_deg: 28.0 },
    ItaClass { name: "brown", label: "brown (−30–10°)", min_deg: -30.0, max_deg: 10.0 },
    ItaClass { name: "dark", label: "dark (< −30°)", min_deg: f64::NEG_INFINITY, max_deg: -30.0 },
];

/// The class of an angle (None for NaN).
pub fn ita_class(ita_deg: f64) -> Option<&'static ItaClass> {
    ITA_CLASSES.iter().find(|c| (c.min_deg..c.max_deg).contains(&ita_deg))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_tile_the_angles_lightest_first() {
        for pair in ITA_CLASSES.windows(2) {
            assert_eq!(pair[0].min_deg, pair[1].max_deg, "{} / {}", pair[0].name, pair[1].name);
        }
        assert_eq!(ita_class(55.0).map(|c| c.name), Some("very-light"));
        assert_eq!(ita_class(54.999).map(|c| c.name), Some("light"));
        assert_eq!(ita_class(-30.0).map(|c| c.name), Some("brown"));
        assert_eq!(ita_class(-90.0).map(|c| c.name), Some("dark"));
        assert_eq!(ita_class(f64::NAN), None);
    }

    #[test]
    fn angle_of_known_colours() {
        // L* 50 is 0° whatever b*; L* 60, b* 10 is 45°; b* = 0 above L* 50 is 90°.
        assert_eq!(ita_degrees([50.0, 5.0, 12.0]), 0.0);
        assert!((ita_degrees([60.0, 5.0, 10.0]) - 45.0).abs() < 1e-12);
        assert_eq!(ita_degrees([70.0, 0.0, 0.0]), 90.0);
    }
}
