//! Guarded numerics shared by the physics modules.

/// The `k`th of `n` indices spread evenly by the golden-ratio sequence (frac(k (sqrt 5 - 1) / 2) n): any number of
/// picks covers 0..n with no row or column pattern, for the samples taken from a texture.
pub fn golden_index(k: usize, n: usize) -> usize {
    let golden = (5f64.sqrt() - 1.0) / 2.0;
    (((k as f64 * golden).fract() * n as f64) as usize).min(n.saturating_sub(1))
}

/// The message of a caught panic's payload (a `&str` or `String` panic), or `None` for another payload.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> Option<String> {
    payload.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| payload.downcast_ref::<String>().cloned())
}

/// `a / b`, or `fallback` when `b` is zero or the quotient is not finite.
pub fn safe_div(a: f64, b: f64, fallback: f64) -> f64 {
    let q = a / b;
    if q.is_finite() {
        q
    } else {
        fallback
    }
}

/// `max(x, 0)`, mapping NaN and -0.0 to 0.
pub fn clamp_zero(x: f64) -> f64 {
    if x > 0.0 {
        x
    } else {
        0.0
    }
}

/// `x` clamped to [lo, hi], NaN mapped to `lo` (and -infinity to `lo`, +infinity to `hi`). Unlike [`clamp_zero`]
/// it keeps the sign of `x == lo` (-0.0 stays -0.0 for lo = 0).
pub fn clamp_nan_to_low(x: f64, lo: f64, hi: f64) -> f64 {
    if x >= lo {
        x.min(hi)
    } else {
        lo
    }
}

/// `(1 - e^(-a q)) / (1 - e^(-b q))` for a, b > 0 and q >= 0, exact to rounding for every q, including its limit a / b at q = 0.
/// It is the sum of a geometric series of multipole images (see `diffusion::multipole`).
pub fn expm1_ratio(a: f64, b: f64, q: f64) -> f64 {
    let den = -(-b * q).exp_m1();
    if den > 0.0 {
        -(-a * q).exp_m1() / den
    } else {
        a / b
    }
}

/// `(P_n(z), P_n'(z))`: Legendre polynomial of degree n and its derivative, by the three-term recurrence
/// (Abramowitz & Stegun 8.5.3, 8.5.4); |z| < 1.
fn legendre_and_derivative(n: usize, z: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, 0.0);
    for j in 0..n {
        let p2 = p1;
        p1 = p0;
        p0 = ((2 * j + 1) as f64 * z * p1 - j as f64 * p2) / (j + 1) as f64;
    }
    (p0, n as f64 * (z * p0 - p1) / (z * z - 1.0))
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on the Legendre recurrence).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (p, dp) = legendre_and_derivative(n, z);
            let dz = p / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                let (_, dp) = legendre_and_derivative(n, z);
                x[i] = -z;
                w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
                break;
            }
        }
    }
    (x, w)
}

/// Composite Gauss-Legendre rule: the `order`-point rule on each panel between consecutive `breaks` (nodes
/// `a + h (x_i + 1)`, weights `h w_i`, with `h` half the panel's width), panel after panel.
pub fn composite_gauss_legendre(breaks: &[f64], order: usize) -> (Vec<f64>, Vec<f64>) {
    let (x, w) = gauss_legendre(order);
    let mut nodes = Vec::with_capacity(order * breaks.len());
    let mut weights = Vec::with_capacity(order * breaks.len());
    for panel in breaks.windows(2) {
        let half = 0.5 * (panel[1] - panel[0]);
        for (xi, wi) in x.iter().zip(&w) {
            nodes.push(panel[0] + half * (xi + 1.0));
            weights.push(half * wi);
        }
    }
    (nodes, weights)
}

/// A bracket after [`bisect`]: `lo` below the switch point, `hi` at or above it, and the last midpoint tested.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bisection {
    pub lo: f64,
    pub hi: f64,
    pub last_midpoint: f64,
}

/// `steps` halvings of [lo, hi] towards the point where `at_or_above(x)` switches from false to true: each step
/// tests `mid = (lo + hi) / 2` and moves `hi` there if it holds, `lo` otherwise. With no steps, `last_midpoint` is
/// the midpoint of the bracket given.
pub fn bisect(lo: f64, hi: f64, steps: usize, mut at_or_above: impl FnMut(f64) -> bool) -> Bisection {
    let (mut lo, mut hi) = (lo, hi);
    let mut mid = 0.5 * (lo + hi);
    for _ in 0..steps {
        mid = 0.5 * (lo + hi);
        if at_or_above(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Bisection { lo, hi, last_midpoint: mid }
}

/// Root of `f` in a bracket by the Illinois variant of regula falsi (Dowell & Jarratt 1971, BIT 11, 168): the
/// secant through the bracket's ends, halving the value kept at an end that stays twice in a row (superlinear,
/// order ~1.44). `(lo, f_lo)` and `(hi, f_hi)` are the bracket with `f` already evaluated, of opposite signs.
/// Stops after `max_steps`, on an exact zero, when the ends' values are equal or when the bracket is within one
/// ulp-scale of `hi` (`hi - lo <= EPSILON hi`). Returns the last secant point (`lo` if no step was taken).
pub fn illinois(
    (mut lo, mut f_lo): (f64, f64),
    (mut hi, mut f_hi): (f64, f64),
    max_steps: usize,
    mut f: impl FnMut(f64) -> f64,
) -> f64 {
    let mut x = lo;
    let mut side = 0;
    for _ in 0..max_steps {
        if f_hi == f_lo || hi - lo <= f64::EPSILON * hi {
            break;
        }
        x = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        let fx = f(x);
        if fx == 0.0 {
            break;
        }
        if (fx < 0.0) == (f_lo < 0.0) {
            lo = x;
            f_lo = fx;
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        } else {
            hi = x;
            f_hi = fx;
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        }
    }
    x
}

/// Minimiser of a unimodal `f` on [a, b] by golden-section search (Kiefer 1953), until the bracket is narrower than
/// `tolerance`; returns the final bracket (a, b). The Burley fit's reference (its tests): the fit itself refines by
/// [`newton_min`].
#[cfg(test)]
pub fn golden_section_min(a: f64, b: f64, tolerance: f64, mut f: impl FnMut(f64) -> f64) -> (f64, f64) {
    let (mut a, mut b) = (a, b);
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut e) = (b - phi * (b - a), a + phi * (b - a));
    let (mut fc, mut fe) = (f(c), f(e));
    while b - a > tolerance {
        if fc < fe {
            b = e;
            e = c;
            fe = fc;
            c = b - phi * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = e;
            fc = fe;
            e = a + phi * (b - a);
            fe = f(e);
        }
    }
    (a, b)
}

/// Minimiser of a smooth `f` on [a, b] from its slope and curvature (`slope_curvature(x) = (f'(x), f''(x))`), from
/// `start` inside: Newton's steps towards the slope's root, each kept inside the bracket the slopes' signs have
/// narrowed, with a bisection of the bracket instead where a step would leave it or the curvature is not positive.
/// Stops when a Newton step is at most `tolerance` (quadratic convergence: the error after it is far smaller), when a
/// bisected bracket is at most `tolerance` wide, on a zero slope or after `max_steps`; returns the last point. Where f
/// falls all the way to an end, it ends within `tolerance` of that end. For a unimodal f it finds what
/// [`golden_section_min`] does in a handful of steps instead of some 35 (each needs both derivatives).
pub fn newton_min(
    a: f64,
    b: f64,
    start: f64,
    tolerance: f64,
    max_steps: usize,
    mut slope_curvature: impl FnMut(f64) -> (f64, f64),
) -> f64 {
    let (mut a, mut b, mut x) = (a, b, start);
    for _ in 0..max_steps {
        let (slope, curvature) = slope_curvature(x);
        if slope == 0.0 {
            break;
        }
        if slope > 0.0 {
            b = x;
        } else {
            a = x;
        }
        let newton = x - slope / curvature;
        let (next, converged) = if curvature > 0.0 && newton > a && newton < b {
            (newton, (newton - x).abs() <= tolerance)
        } else {
            (0.5 * (a + b), b - a <= tolerance)
        };
        x = next;
        if converged {
            break;
        }
    }
    x
}

/// `|a - b| / |b|`: the relative error of `a` against the reference `b`, for the tests' tolerances.
#[cfg(test)]
pub fn relative_error(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// `table[n][j] = P_n(x_j)`, Legendre polynomials of degree n < `order` at the points `x` (three-term recurrence).
pub fn legendre_table(order: usize, x: &[f64]) -> Vec<Vec<f64>> {
    let mut table = vec![vec![1.0; x.len()]; order];
    if order > 1 {
        table[1] = x.to_vec();
    }
    for n in 1..order.saturating_sub(1) {
        let next: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(j, &xj)| ((2 * n + 1) as f64 * xj * table[n][j] - n as f64 * table[n - 1][j]) / (n + 1) as f64)
            .collect();
        table[n + 1] = next;
    }
    table
}

/// Spherical Bessel functions `j_n(x)` for n < `count` and x > 0: upward recurrence from j_0, j_1 where it is stable
/// (n < x), Miller's downward recurrence normalised by sum (2n+1) j_n^2 = 1 otherwise (Abramowitz & Stegun 10.1.50,
/// 10.1.19; Numerical Recipes 6.7).
pub fn spherical_bessel_j(count: usize, x: f64) -> Vec<f64> {
    let mut out = vec![0.0; count];
    if count == 0 {
        return out;
    }
    if x >= count as f64 {
        let (s, c) = x.sin_cos();
        out[0] = s / x;
        if count > 1 {
            out[1] = s / (x * x) - c / x;
        }
        for n in 1..count.saturating_sub(1) {
            out[n + 1] = (2 * n + 1) as f64 / x * out[n] - out[n - 1];
        }
        return out;
    }
    let start = count + 40 + x as usize;
    let mut values = vec![0.0; start + 2];
    values[start] = 1.0;
    for n in (1..=start).rev() {
        values[n - 1] = (2 * n + 1) as f64 / x * values[n] - values[n + 1];
        if values[n - 1].abs() > 1e100 {
            for v in values[n - 1..].iter_mut() {
                *v *= 1e-100;
            }
        }
    }
    let norm: f64 = values.iter().enumerate().map(|(n, v)| (2 * n + 1) as f64 * v * v).sum::<f64>().sqrt();
    // The sign from whichever of j_0, j_1 is larger in closed form.
    let (s, c) = x.sin_cos();
    let (j0, j1) = (s / x, s / (x * x) - c / x);
    let sign = if j0.abs() >= j1.abs() { (j0 * values[0]).signum() } else { (j1 * values[1]).signum() };
    for (o, v) in out.iter_mut().zip(&values) {
        *o = sign * v / norm;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expm1_ratio_limits() {
        assert_eq!(expm1_ratio(1.0, 4.0, 0.0), 0.25);
        assert!((expm1_ratio(1.0, 4.0, 1e-300) - 0.25).abs() < 1e-15, "{}", expm1_ratio(1.0, 4.0, 1e-300));
        let q: f64 = 0.3;
        let direct = (1.0 - (-q).exp()) / (1.0 - (-4.0 * q).exp());
        assert!((expm1_ratio(1.0, 4.0, q) - direct).abs() < 1e-15, "{} vs {direct}", expm1_ratio(1.0, 4.0, q));
        assert_eq!(expm1_ratio(1.0, 4.0, 1e6), 1.0);
    }

    /// Spherical Bessel functions against their closed forms j_2 = (3/x^3 - 1/x) sin x - 3 cos x / x^2, on both
    /// sides of the switch between the recurrences, and the small-argument limit x^n / (2n+1)!!.
    #[test]
    fn spherical_bessel_closed_forms() {
        for x in [0.7, 3.0, 11.9, 12.0, 40.0, 1e4] {
            let j = spherical_bessel_j(12, x);
            let (s, c) = (x.sin(), x.cos());
            let j2 = (3.0 / (x * x * x) - 1.0 / x) * s - 3.0 * c / (x * x);
            assert!((j[0] - s / x).abs() < 1e-14 && (j[2] - j2).abs() < 1e-12 * j2.abs().max(1e-3), "x={x}: {j:?}");
        }
        let j = spherical_bessel_j(12, 1e-3);
        let double_factorial_21: f64 = (1..=21).step_by(2).map(|k| k as f64).product();
        assert!((j[10] / (1e-30 / double_factorial_21) - 1.0).abs() < 1e-6, "{}", j[10]);
    }

    /// int_0^2 x^7 dx = 32 on three unequal panels with 4 nodes each (exact for degree <= 7), and the rule's length.
    #[test]
    fn composite_rule_integrates_polynomials() {
        let (x, w) = composite_gauss_legendre(&[0.0, 0.1, 1.3, 2.0], 4);
        assert_eq!((x.len(), w.len()), (12, 12));
        assert!(x.windows(2).all(|p| p[1] > p[0]) && x[0] > 0.0 && x[11] < 2.0, "{x:?}");
        let integral: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(7)).sum();
        assert!((integral - 32.0).abs() < 1e-12, "{integral}");
    }

    #[test]
    fn nan_safe_clamps() {
        assert_eq!(clamp_nan_to_low(f64::NAN, 0.2, 0.9), 0.2);
        assert_eq!(clamp_nan_to_low(f64::NEG_INFINITY, 0.2, 0.9), 0.2);
        assert_eq!(clamp_nan_to_low(f64::INFINITY, 0.2, 0.9), 0.9);
        assert_eq!(clamp_nan_to_low(0.5, 0.2, 0.9), 0.5);
        assert!(clamp_nan_to_low(-0.0, 0.0, 1.0).is_sign_negative(), "{:?}", clamp_nan_to_low(-0.0, 0.0, 1.0));
        assert_eq!(clamp_zero(f64::NAN), 0.0);
        assert!(clamp_zero(-0.0).is_sign_positive(), "{:?}", clamp_zero(-0.0));
        assert_eq!(clamp_zero(-3.0), 0.0);
        assert_eq!(clamp_zero(f64::INFINITY), f64::INFINITY);
    }

    /// sqrt(2) as the switch point of x^2 >= 2 on [1, 2]: 52 halvings leave a bracket of 2^-52 around it.
    #[test]
    fn bisect_finds_sqrt_two() {
        let b = bisect(1.0, 2.0, 52, |x| x * x >= 2.0);
        assert!(b.lo < std::f64::consts::SQRT_2 && b.hi >= std::f64::consts::SQRT_2, "{b:?}");
        assert!(b.hi - b.lo <= 2f64.powi(-52), "{b:?}");
        assert!(b.last_midpoint == b.lo || b.last_midpoint == b.hi, "{b:?}");
        assert_eq!(bisect(1.0, 2.0, 0, |_| true).last_midpoint, 1.5);
        assert_eq!(bisect(0.0, 1.0, 1, |_| true), Bisection { lo: 0.0, hi: 0.5, last_midpoint: 0.5 });
    }

    /// The root of cos x = x (the Dottie number 0.7390851332151607) and the cube root of 3, to rounding.
    #[test]
    fn illinois_finds_known_roots() {
        let g = |x: f64| x.cos() - x;
        let root = illinois((0.0, g(0.0)), (1.0, g(1.0)), 100, g);
        assert!((root - 0.739_085_133_215_160_7).abs() < 1e-15, "{root}");
        let h = |x: f64| x * x * x - 3.0;
        let root = illinois((1.0, h(1.0)), (2.0, h(2.0)), 100, h);
        assert!((root - 3f64.cbrt()).abs() < 1e-15, "{root}");
        assert_eq!(illinois((1.0, -1.0), (2.0, -1.0), 100, h), 1.0);
    }

    /// The minimum of (x - 0.3)^2 + 1 on [-1, 2] and of x - ln x (at x = 1) on [0.1, 5]. A minimum is located only to
    /// ~sqrt(EPSILON) relative (1.5e-8 here): closer in, f differs from f(x*) by less than its rounding.
    #[test]
    fn golden_section_finds_known_minima() {
        let (a, b) = golden_section_min(-1.0, 2.0, 1e-9, |x| (x - 0.3) * (x - 0.3) + 1.0);
        assert!(b - a <= 1e-9 && (0.5 * (a + b) - 0.3).abs() < 5e-8, "{a} {b}");
        let (a, b) = golden_section_min(0.1, 5.0, 1e-9, |x| x - x.ln());
        assert!((0.5 * (a + b) - 1.0).abs() < 5e-8, "{a} {b}");
        let (a, b) = golden_section_min(0.0, 3.0, 1e-6, |x| (x - 2.0).abs());
        assert!(b - a <= 1e-6 && a <= 2.0 && b >= 2.0, "{a} {b}");
    }

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let (x, w) = gauss_legendre(8);
        let integral: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(14)).sum();
        assert!((integral - 2.0 / 15.0).abs() < 1e-14, "{integral} vs {}", 2.0 / 15.0);
        assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-14, "{}", w.iter().sum::<f64>());
    }

    #[test]
    fn panic_messages_are_read_from_both_payload_kinds() {
        let text = std::panic::catch_unwind(|| panic!("plain")).unwrap_err();
        let formatted = std::panic::catch_unwind(|| panic!("formatted {}", 7)).unwrap_err();
        let other = std::panic::catch_unwind(|| std::panic::panic_any(7u8)).unwrap_err();
        assert_eq!(panic_message(text.as_ref()).as_deref(), Some("plain"));
        assert_eq!(panic_message(formatted.as_ref()).as_deref(), Some("formatted 7"));
        assert_eq!(panic_message(other.as_ref()), None);
    }
}
