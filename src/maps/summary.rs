//! What the strategy decision reads of a whole texture ([`Summary`]): gathered from one image, or merged from a UDIM
//! set's tiles read one at a time, so that a set is decided as one texture without holding its tiles at once.

use std::collections::HashSet;

use rayon::prelude::*;

use super::io::{ParamImage, Plane, ALL_CHANNELS};
use super::report::MAX_DISTINCT_TUPLES;
use crate::skin::params::{ParamSpec, EPIDERMIS_THICKNESS, MATERIAL_PARAMS};

/// A material texel's tuple: its values of [`MATERIAL_PARAMS`] (oiliness does not enter the material).
pub type Tuple = [f32; 6];

/// The index in [`ALL_CHANNELS`] (an image's plane order) of a parameter.
pub(crate) fn channel(spec: &ParamSpec) -> usize {
    ALL_CHANNELS.iter().position(|name| *name == spec.name).expect("every parameter has a plane")
}

/// What the strategy decision reads of a whole texture: gathered from one image ([`Summary::of`]) or merged from a
/// tile set's ([`Summary::merge`]), so that a set is decided as one texture without holding its tiles at once.
#[derive(Debug, Clone)]
pub struct Summary {
    pub width: usize,
    pub texels: usize,
    /// Each plane's value where it holds one value everywhere ([`ALL_CHANNELS`] order).
    pub uniform: [Option<f32>; 7],
    /// The distinct material tuples (f32 bit patterns) when there are at most [`MAX_DISTINCT_TUPLES`].
    pub tuples: Option<HashSet<[u32; 6]>>,
    /// The least and greatest epidermis thickness, mm.
    pub thickness_mm: [f32; 2],
    /// The tuples of the texels a table stack over thickness is checked at (golden-ratio spaced).
    pub check_texels: Vec<Tuple>,
    /// The readers' notes ([`ParamImage::notes`]).
    pub notes: Vec<String>,
}

impl Summary {
    /// The summary of one checked image, with `check_samples` check texels.
    pub fn of(image: &ParamImage, check_samples: usize) -> Summary {
        let uniform: [Option<f32>; 7] = std::array::from_fn(|p| uniform_value(image.plane(p)));
        let n = image.texel_count();
        let planes = MATERIAL_PARAMS.map(|spec| image.plane_of(&spec));
        let tuple = |i: usize| planes.map(|plane| plane.value(i));
        let tuples = if MATERIAL_PARAMS.iter().all(|s| uniform[channel(s)].is_some()) {
            Some(std::iter::once(tuple(0).map(f32::to_bits)).collect())
        } else {
            distinct_tuples(n, tuple)
        };
        let thickness_mm = match image.plane_of(&EPIDERMIS_THICKNESS) {
            Plane::Constant(v) => [*v, *v],
            Plane::Texels(values) => values
                .par_iter()
                .fold(|| [f32::INFINITY, f32::NEG_INFINITY], |[a, b], &t| [a.min(t), b.max(t)])
                .reduce(|| [f32::INFINITY, f32::NEG_INFINITY], |x, y| [x[0].min(y[0]), x[1].max(y[1])]),
        };
        let check_texels = (0..check_samples.min(n)).map(|k| tuple(crate::numeric::golden_index(k, n))).collect();
        Summary {
            width: image.width,
            texels: n,
            uniform,
            tuples,
            thickness_mm,
            check_texels,
            notes: image.notes.clone(),
        }
    }

    /// The summary of the texture made of these parts stacked (a UDIM set's tiles, in order), with at most
    /// `check_samples` check texels picked from the parts'.
    pub fn merge(parts: Vec<Summary>, check_samples: usize) -> Summary {
        let texels = parts.iter().map(|s| s.texels).sum();
        let uniform = std::array::from_fn(|p| {
            let first = parts.first().and_then(|s| s.uniform[p])?;
            parts.iter().all(|s| s.uniform[p].map(f32::to_bits) == Some(first.to_bits())).then_some(first)
        });
        let mut tuples: Option<HashSet<[u32; 6]>> = Some(HashSet::new());
        for part in &parts {
            tuples = match (tuples, &part.tuples) {
                (Some(mut all), Some(these)) => {
                    all.extend(these);
                    (all.len() <= MAX_DISTINCT_TUPLES).then_some(all)
                }
                _ => None,
            };
        }
        let thickness_mm = parts
            .iter()
            .fold([f32::INFINITY, f32::NEG_INFINITY], |[a, b], s| [a.min(s.thickness_mm[0]), b.max(s.thickness_mm[1])]);
        let pool: Vec<Tuple> = parts.iter().flat_map(|s| s.check_texels.iter().copied()).collect();
        let check_texels =
            (0..check_samples.min(pool.len())).map(|k| pool[crate::numeric::golden_index(k, pool.len())]).collect();
        Summary {
            width: parts.first().map_or(0, |s| s.width),
            texels,
            uniform,
            tuples,
            thickness_mm,
            check_texels,
            notes: parts.into_iter().flat_map(|s| s.notes).collect(),
        }
    }

    /// The value of a parameter where it is one everywhere.
    pub(crate) fn uniform_of(&self, spec: &ParamSpec) -> Option<f32> {
        self.uniform[channel(spec)]
    }
}

/// The plane's value if every texel holds the same one (a constant, or a map that is constant in fact).
fn uniform_value(plane: &Plane) -> Option<f32> {
    match plane {
        Plane::Constant(v) => Some(*v),
        Plane::Texels(values) => {
            let first = values.first()?.to_bits();
            values.par_iter().all(|v| v.to_bits() == first).then(|| f32::from_bits(first))
        }
    }
}

/// The distinct tuples of `texels` texels (f32 bit patterns) if there are at most [`MAX_DISTINCT_TUPLES`], else None.
fn distinct_tuples(texels: usize, tuple: impl Fn(usize) -> Tuple) -> Option<HashSet<[u32; 6]>> {
    let mut set = HashSet::new();
    for i in 0..texels {
        set.insert(tuple(i).map(f32::to_bits));
        if set.len() > MAX_DISTINCT_TUPLES {
            return None;
        }
    }
    Some(set)
}
