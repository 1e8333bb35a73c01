"""An independent reference for Cycles' random-walk subsurface scattering in a thin flat slab: a Monte Carlo of the
walk as the Cycles source describes it (docs/blender-targets.md, with the Cycles source lines), in numpy.

Used by the length-scale test (tests/blender/test_versions.py) and the calibration
(scripts/calibration/calibrate_random_walk.py): a slab of thickness T under a sun from straight above, seen from
straight above, renders piL/E = the probability that a walk entering the top face leaves through the top face again
(the walk's throughput is divided by Base Color, which the closure weight multiplies back; the exit point gathers the
sun with a Lambertian of weight 1). Only the top face is lit and the world is black, so walks leaving through the
bottom are lost.

Cycles' walk (intern/cycles/kernel/integrator/subsurface_random_walk.h, closure/bssrdf.h, kernel/types.h):
- isotropic phase (anisotropy 0), at most 256 segments (BSSRDF_MAX_BOUNCES), exit at the first boundary crossing (no
  Fresnel, no internal reflection), entry by refraction at the main IOR: with Specular IOR Level 0 that IOR is 1.01
  (the clamp in bssrdf.h), so a camera ray at normal incidence enters straight down;
- single-scattering albedo alpha from Base Color A: the Wrenninge/Chiang fit (RANDOM_WALK up to 5.1,
  RANDOM_WALK_LEGACY and RANDOM_WALK_SKIN) or van de Hulst's inversion (RANDOM_WALK from 5.2), clamped to 0.999999;
- mean free path: Radius*Scale/(4 pi) (old RANDOM_WALK, RANDOM_WALK_LEGACY), Radius*Scale (RANDOM_WALK from 5.2),
  Radius*Scale*sqrt(3(1 - alpha')) with alpha' from a dipole inversion of A at the Subsurface IOR (RANDOM_WALK_SKIN).
"""

from __future__ import annotations

import math

import numpy as np

MAX_SEGMENTS = 256  # BSSRDF_MAX_BOUNCES, intern/cycles/kernel/types.h
ALPHA_MAX = 0.999999  # clamp in subsurface_random_walk_remap


def alpha_wrenninge(albedo: float) -> float:
    """Single-scattering albedo from Base Color, Cycles' fit at anisotropy g = 0 (subsurface_random_walk_remap in
    intern/cycles/kernel/integrator/subsurface_random_walk.h, constants from Wrenninge et al., evaluated at g = 0)."""
    a, b, c, d, e, f = 1.82605, 5.11247, 1.09686, 0.49631, 4.23501, 2.40603
    blend = albedo**0.25
    alpha = (1 - blend) * a * math.atan(b * albedo) ** c + blend * d * math.atan(e * albedo) ** f
    return min(alpha, ALPHA_MAX)


def alpha_van_de_hulst(albedo: float) -> float:
    """Single-scattering albedo from Base Color, van de Hulst's inversion as Cycles uses it from 5.2 on (d'Eon, "A
    Hitchhiker's Guide to Multiple Scattering", eq. 53.7; Blender commit 695bae346), g = 0."""
    s = 4.09712 + 4.20863 * albedo - math.sqrt(9.59217 + 41.6808 * albedo + 17.7126 * albedo**2)
    return min(1.0 - s * s, ALPHA_MAX)


def skin_radius_factor(albedo: float, ior: float) -> float:
    """RANDOM_WALK_SKIN's radius factor sqrt(3 (1 - alpha')), alpha' from the dipole inversion of A at the Subsurface
    IOR eta (bssrdf_setup_radius in intern/cycles/kernel/closure/bssrdf.h: 12 bisection steps)."""
    f_dr = -1.440 / ior**2 + 0.710 / ior + 0.668 + 0.0636 * ior
    a_f = (4.0 / 3.0) * (1 + f_dr) / (1 - f_dr)

    def rd(alpha_p: float) -> float:
        s = math.sqrt(3 * (1 - alpha_p))
        return 0.5 * alpha_p * (1 + math.exp(-a_f * s)) * math.exp(-s)

    lo, hi = 0.0, 1.0
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        if rd(mid) > albedo:
            hi = mid
        else:
            lo = mid
    alpha_p = 0.5 * (lo + hi)
    return math.sqrt(3 * (1 - alpha_p))


def slab_top_exit(
    thickness_mfp: float,
    alpha: float,
    paths: int = 400_000,
    seed: int = 1,
    diffuse_entry_fraction: float = 0.0,
) -> tuple[float, float]:
    """Monte Carlo of the walk in an index-matched slab `thickness_mfp` mean free paths thick, isotropic scattering
    with single-scattering albedo `alpha`: the mean throughput of walks that leave through the top face (entry at the
    top; a fraction `diffuse_entry_fraction` of them enters in a cosine-distributed direction, the rest straight
    down). Returns (estimate, standard error)."""
    rng = np.random.default_rng(seed)
    z = np.zeros(paths)  # depth in mean free paths, 0 = top face, positive downwards
    mu = np.ones(paths)  # direction cosine along +depth
    diffuse = rng.random(paths) < diffuse_entry_fraction
    mu[diffuse] = np.sqrt(rng.random(int(diffuse.sum())))
    weight = np.ones(paths)
    out = np.zeros(paths)
    alive = np.ones(paths, dtype=bool)
    for _ in range(MAX_SEGMENTS):
        idx = np.nonzero(alive)[0]
        if idx.size == 0:
            break
        z[idx] += mu[idx] * -np.log1p(-rng.random(idx.size))
        top = z[idx] < 0
        bottom = z[idx] > thickness_mfp
        out[idx[top]] = weight[idx[top]]
        alive[idx[top | bottom]] = False
        inside = idx[~(top | bottom)]
        weight[inside] *= alpha
        mu[inside] = 2 * rng.random(inside.size) - 1
    return float(out.mean()), float(out.std() / math.sqrt(paths))


def subsurface_methods() -> list[str]:
    """The Principled BSDF subsurface method ids the running bpy offers."""
    import bpy

    prop = bpy.types.ShaderNodeBsdfPrincipled.bl_rna.properties["subsurface_method"]
    return [item.identifier for item in prop.enum_items]


ALPHA_MODELS = {"wrenninge_fit": alpha_wrenninge, "van_de_hulst": alpha_van_de_hulst}


def mean_free_path_per_radius(model: dict, albedo: float, ior: float = 1.4) -> float:
    """The walk's mean free path per unit Radius*Scale (g = 0) under a random-walk model of the core's Blender target
    table (``blender_targets()["versions"][i]["methods"][j]["model"]``): "four_pi_mean_free_path" (Radius*Scale =
    4 pi mfp: RANDOM_WALK before 5.2, RANDOM_WALK_LEGACY), "mean_free_path" (RANDOM_WALK from 5.2), "skin_dipole"
    (RANDOM_WALK_SKIN, at the Subsurface IOR `ior`)."""
    radius = model["radius"]
    if radius == "four_pi_mean_free_path":
        return 1.0 / (4 * math.pi)
    if radius == "mean_free_path":
        return 1.0
    if radius == "skin_dipole":
        return skin_radius_factor(albedo, ior)
    raise ValueError(f"radius convention {radius!r}: expected four_pi_mean_free_path, mean_free_path or skin_dipole")


def walk_alpha(model: dict, albedo: float) -> float:
    """The single-scattering albedo the walk of a core random-walk model uses for Base Color `albedo` (g = 0)."""
    return ALPHA_MODELS[model["alpha"]](albedo)


def core_target(version: tuple[int, ...]) -> dict:
    """The core's table row for a tested Blender version (spectral_skin.blender_targets(); every version the tests
    run in has its own row)."""
    import spectral_skin

    rows = spectral_skin.blender_targets()["versions"]
    name = "{}.{}".format(*version[:2])
    found = [r for r in rows if r["version"] == name]
    assert found, f"Blender {name} has no row of its own in the core's table ({[r['version'] for r in rows]})"
    return found[0]


def core_walk_models(version: tuple[int, ...]) -> dict[str, dict]:
    """Blender enum id -> the core's random-walk model, for the methods the core maps as walks in this version."""
    return {m["blender_id"]: m["model"] for m in core_target(version)["methods"] if m["model"]["kind"] == "random_walk"}
