"""Cycles scene helpers shared by the Blender render tests (tests/blender, whose conftest.py puts scripts/lib on
sys.path) and the measurement scripts (scripts/reports, scripts/calibration): scene set-up, materials, rendering,
EXR input/output and the Burley edge model. No pytest here (the fixtures live in tests/blender/conftest.py), so a
script imports this module as it is.

Everything here imports bpy lazily, so collecting this directory without bpy installed does not fail: the test
modules themselves call ``pytest.importorskip("bpy")``.

Scene conventions (see docs/blender-principled.md, sections Flat slab under a white world, Edge and spot renders and
Test scenes): the scene unit is the metre, the slab's top face is the plane z = 0, the camera is orthographic and
looks straight down (image x = world +x, image up = world +y), and every render is Cycles CPU with a fixed seed, no
adaptive sampling, no denoising, no clamping, Raw view, written to a 32-bit float EXR and read back with OpenImageIO.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Sequence

import numpy as np

MM = 0.001  # metres per millimetre: Subsurface Scale for radii given in mm

# Blender 4.2 renders a subsurface channel whose Radius x Scale is below about a quarter of a pixel as plain diffuse
# with its Base Color, and then biases the other channels' estimate (measured in 4.2.23: docs/blender-render-tests.md;
# 4.5 and later do not). A render compared with the core is seen close enough that every channel's radius spans at
# least this many pixels (span_resolving):
RESOLVED_RADIUS_PX = 1.0


def span_resolving(radius_mm, width_px: int, widest_m: float) -> float:
    """The image width in metres, at most widest_m, at which the smallest of radius_mm (any shape, mm at Subsurface
    Scale MM) spans RESOLVED_RADIUS_PX pixels of a width_px-wide image."""
    smallest_m = float(np.min(np.asarray(radius_mm, dtype=np.float64))) * MM
    return min(widest_m, smallest_m * width_px / RESOLVED_RADIUS_PX)

# numpy >= 2 renamed trapz (bpy 5.0 ships numpy 1.26)
_trapezoid = getattr(np, "trapezoid", None) or np.trapz


def _bpy():
    import bpy

    return bpy


def reset_scene():
    """A fresh empty factory scene, set up for deterministic Cycles CPU rendering; returns the scene."""
    bpy = _bpy()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cy = scene.cycles
    cy.device = "CPU"
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.seed = 1
    cy.use_animated_seed = False
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    cy.use_auto_tile = False
    # The sample counts of the tests were chosen by noise measured with 5.0's factory pattern, Tabulated Sobol (which
    # stratifies Burley's disk sampling); 4.2, 4.5 and 5.3 default to "Automatic" (blue noise): set it everywhere.
    cy.sampling_pattern = "TABULATED_SOBOL"
    scene.render.threads_mode = "AUTO"
    scene.render.use_persistent_data = False
    scene.view_settings.view_transform = "Raw"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGBA"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    return scene


def eevee_engine_id() -> str:
    """This Blender's EEVEE engine id (BLENDER_EEVEE_NEXT in 4.2-4.5, BLENDER_EEVEE from 5.0)."""
    bpy = _bpy()
    ids = [i.identifier for i in bpy.types.RenderSettings.bl_rna.properties["engine"].enum_items]
    return [i for i in ids if "EEVEE" in i][-1]


def set_world(scene, strength: float, color: Sequence[float] = (1.0, 1.0, 1.0)):
    """A uniform world (Background shader) of the given colour and strength."""
    bpy = _bpy()
    world = bpy.data.worlds.new("World")
    if world.node_tree is None:  # Blender < 5.0 (use_nodes is deprecated in 5.0, where node trees always exist)
        world.use_nodes = True
    bg = world.node_tree.nodes.get("Background")
    if bg is None:
        bg = world.node_tree.nodes.new("ShaderNodeBackground")
        out = world.node_tree.nodes.get("World Output") or world.node_tree.nodes.new("ShaderNodeOutputWorld")
        world.node_tree.links.new(bg.outputs["Background"], out.inputs["Surface"])
    bg.inputs["Color"].default_value = (*color, 1.0)
    bg.inputs["Strength"].default_value = strength
    scene.world = world
    return world


def add_box(name: str, x0: float, x1: float, y0: float, y1: float, z0: float, z1: float):
    """An axis-aligned box with its vertices in world coordinates (object at the origin, unit scale, so Object
    texture coordinates are world coordinates in metres)."""
    bpy = _bpy()
    verts = [(x, y, z) for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)]
    # vertex index = 4*iz + 2*iy + ix; outward-facing quads
    faces = [
        (0, 2, 3, 1),  # bottom (-z)
        (4, 5, 7, 6),  # top (+z)
        (0, 1, 5, 4),  # -y
        (2, 6, 7, 3),  # +y
        (0, 4, 6, 2),  # -x
        (1, 3, 7, 5),  # +x
    ]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def add_slab(size: float = 1.0, thickness: float = 0.2):
    """The test slab: size x size x thickness metres, centred on the z axis, top face at z = 0."""
    h = size / 2
    return add_box("Slab", -h, h, -h, h, -thickness, 0.0)


def add_plane(name: str, x0: float, x1: float, y0: float, y1: float, z: float):
    """A single upward-facing quad at height z."""
    bpy = _bpy()
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([(x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)], [], [(0, 1, 2, 3)])
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def add_top_camera(scene, ortho_scale: float, width: int, height: int, center=(0.0, 0.0), z: float = 1.0):
    """Orthographic camera looking straight down at (center, 0); ortho_scale spans the image width (width >= height)."""
    bpy = _bpy()
    cam_data = bpy.data.cameras.new("Camera")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = ortho_scale
    cam_data.sensor_fit = "HORIZONTAL"
    cam_data.clip_start = 1e-3
    cam_data.clip_end = 10.0
    cam = bpy.data.objects.new("Camera", cam_data)
    cam.location = (center[0], center[1], z)
    cam.rotation_euler = (0.0, 0.0, 0.0)  # looks down -z, image x = +x, image up = +y
    scene.collection.objects.link(cam)
    scene.camera = cam
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene.render.pixel_aspect_x = 1.0
    scene.render.pixel_aspect_y = 1.0
    return cam


def add_sun(scene, strength: float = 1.0, angle: float = 0.0):
    """A sun shining straight down (-z) with irradiance `strength` W/m^2."""
    bpy = _bpy()
    light = bpy.data.lights.new("Sun", type="SUN")
    light.energy = strength
    light.angle = angle
    obj = bpy.data.objects.new("Sun", light)
    obj.rotation_euler = (0.0, 0.0, 0.0)
    scene.collection.objects.link(obj)
    return obj


def _node_material(name: str, bsdf_type: str):
    """A node material holding only a Material Output fed by one new BSDF node; returns (material, bsdf)."""
    bpy = _bpy()
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:  # Blender < 5.0 (use_nodes is deprecated in 5.0, where node trees always exist)
        mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new(bsdf_type)
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return mat, bsdf


def new_material(name: str):
    """A node material with its Principled BSDF and Material Output; returns (material, principled)."""
    return _node_material(name, "ShaderNodeBsdfPrincipled")


def principled_sss(
    name: str,
    method: str,
    base_color: Sequence[float] | None = None,
    radius_mm: Sequence[float] | None = None,
):
    """A Principled BSDF material set up as a pure subsurface scatterer for the flat-slab tests.

    Subsurface Weight 1, Specular IOR Level 0 (no specular closure: docs/blender-principled.md, IOR, Specular IOR Level
    and Roughness), Roughness 0, the given Cycles subsurface method ("BURLEY" or "RANDOM_WALK"), Base Color =
    base_color (linear RGB) and Subsurface Radius = radius_mm with Scale = 0.001 (radii in mm in a metre scene).
    Sockets are set before the method (socket availability changes with the method).
    """
    mat, bsdf = new_material(name)
    inp = bsdf.inputs
    if base_color is not None:
        inp["Base Color"].default_value = (*[float(c) for c in base_color], 1.0)
    inp["Subsurface Weight"].default_value = 1.0
    if radius_mm is not None:
        inp["Subsurface Radius"].default_value = [float(r) for r in radius_mm]
    inp["Subsurface Scale"].default_value = MM
    inp["Specular IOR Level"].default_value = 0.0
    inp["Roughness"].default_value = 0.0
    inp["Metallic"].default_value = 0.0
    inp["Coat Weight"].default_value = 0.0
    inp["Sheen Weight"].default_value = 0.0
    inp["Transmission Weight"].default_value = 0.0
    bsdf.subsurface_method = method
    return mat, bsdf


def black_material(name: str = "Black"):
    """A perfectly absorbing (black diffuse) material."""
    mat, diffuse = _node_material(name, "ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    return mat


def assign(obj, mat):
    obj.data.materials.clear()
    obj.data.materials.append(mat)


def material_snapshot(material) -> dict:
    """Every node's name, type and unlinked input values, and the links: what an untouched material keeps."""
    tree = material.node_tree
    values = {}
    for node in tree.nodes:
        for socket in node.inputs:
            value = getattr(socket, "default_value", None)
            if value is not None:
                values[(node.name, socket.identifier)] = (tuple(value) if hasattr(value, "__len__")
                                                          and not isinstance(value, str) else value)
    links = sorted((lk.from_node.name, lk.from_socket.identifier, lk.to_node.name, lk.to_socket.identifier)
                   for lk in tree.links)
    return {"nodes": sorted((n.name, n.bl_idname) for n in tree.nodes), "values": values, "links": links}


def write_exr(path: str, pixels: np.ndarray) -> None:
    """Write an (H, W, C) float array as a 32-bit float EXR (row 0 = top row)."""
    import OpenImageIO as oiio

    pixels = np.ascontiguousarray(pixels, dtype=np.float32)
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, oiio.FLOAT)
    out = oiio.ImageOutput.create(path)
    assert out is not None, oiio.geterror()
    assert out.open(path, spec), out.geterror()
    assert out.write_image(pixels), out.geterror()
    out.close()


def read_exr(path: str) -> np.ndarray:
    """Read an EXR as float32 (H, W, C), row 0 = top row."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(path)
    assert inp is not None, oiio.geterror()
    pixels = inp.read_image(0, 0, 0, inp.spec().nchannels, oiio.FLOAT)
    inp.close()
    return np.asarray(pixels, dtype=np.float32)


def render(scene, samples: int, filter_width: float = 1.5, seed: int = 1, alpha: bool = False) -> np.ndarray:
    """Render the scene with Cycles to a temporary EXR; returns its RGB (RGBA with ``alpha``) as float64 (H, W, 3|4),
    row 0 = top row (= +y side of the image)."""
    bpy = _bpy()
    scene.cycles.samples = samples
    scene.cycles.seed = seed
    scene.cycles.filter_width = filter_width
    with tempfile.TemporaryDirectory(prefix="spectral_skin_render_") as tmp:
        path = os.path.join(tmp, "render.exr")
        scene.render.filepath = path
        bpy.ops.render.render(write_still=True)
        img = read_exr(path)
    if not (scene.render.use_border and scene.render.use_crop_to_border):  # a cropped border render is smaller
        assert img.shape[:2] == (scene.render.resolution_y, scene.render.resolution_x), img.shape
    return img[:, :, : 4 if alpha else 3].astype(np.float64)


def render_eevee(scene, samples: int) -> np.ndarray:
    """Render the scene with this Blender's EEVEE to a temporary EXR; returns its RGB as float64 (H, W, 3), row 0 = top
    row."""
    bpy = _bpy()
    scene.render.engine = eevee_engine_id()
    scene.eevee.taa_render_samples = samples
    with tempfile.TemporaryDirectory(prefix="spectral_skin_render_") as tmp:
        path = os.path.join(tmp, "render.exr")
        scene.render.filepath = path
        bpy.ops.render.render(write_still=True)
        img = read_exr(path)
    return img[:, :, :3].astype(np.float64)


# The Principled inputs of the skin surface -> the key of evaluate()'s "specular" that holds each.
PRINCIPLED_SURFACE_INPUTS = {"Roughness": "roughness", "IOR": "ior", "Specular IOR Level": "specular_ior_level",
                             "Coat Weight": "coat_weight", "Coat Roughness": "coat_roughness", "Coat IOR": "coat_ior"}


def principled_surface_inputs(specular: dict) -> dict:
    """The surface's Principled inputs (input name -> value) of ``evaluate(...)["specular"]``."""
    return {name: specular[key] for name, key in PRINCIPLED_SURFACE_INPUTS.items()}


def surface_only_material(name: str, inputs: dict):
    """A Principled material that shows its surface reflection alone: Base Color black, Subsurface Weight 0, and the
    given inputs (Principled input name -> value)."""
    mat, bsdf = new_material(name)
    bsdf.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    bsdf.inputs["Subsurface Weight"].default_value = 0.0
    for input_name, value in inputs.items():
        bsdf.inputs[input_name].default_value = value
    return mat


# Normal-incidence surface reflection: one plane per surface, 8 x 8 pixels each, the middle 4 x 4 averaged.
_PLANE_M, _PLANE_PX, _PLANE_EDGE_PX = 0.01, 8, 2


def render_normal_incidence_reflection(surfaces: Sequence[dict], engine: str, samples: int) -> list[float]:
    """The normal-incidence directional albedo Blender renders for each surface: a fresh scene with one plane (z = 0)
    per surface in a row, each a Principled BSDF with the surface's inputs (Principled input name -> value) over Base
    Color black and Subsurface Weight 0, under a uniform white world of strength 1, seen straight down by an
    orthographic camera, so that each plane's pixels are the reflection of its surface along the normal (green
    channel). ``engine``: "cycles" or "eevee"."""
    scene = reset_scene()
    set_world(scene, strength=1.0)
    for i, inputs in enumerate(surfaces):
        plane = add_plane(f"Surface{i}", i * _PLANE_M, (i + 1) * _PLANE_M, 0.0, _PLANE_M, 0.0)
        assign(plane, surface_only_material(f"Surface{i}", inputs))
    n = len(surfaces)
    add_top_camera(scene, ortho_scale=n * _PLANE_M, width=n * _PLANE_PX, height=_PLANE_PX,
                   center=(n * _PLANE_M / 2, _PLANE_M / 2))
    img = render(scene, samples=samples) if engine == "cycles" else render_eevee(scene, samples)
    lo, hi = _PLANE_EDGE_PX, _PLANE_PX - _PLANE_EDGE_PX
    return [float(img[lo:hi, i * _PLANE_PX + lo : i * _PLANE_PX + hi, 1].mean()) for i in range(n)]


# In-plane slices: one coaxial cylinder of radius 1 per surface, 8 pixel rows each, the middle 4 rows averaged.
_SLICE_ROWS_PX, _SLICE_EDGE_PX, _SLICE_SIDES = 8, 2, 720


def render_in_plane_slices(surfaces: Sequence[dict], engine: str, incidences_deg: Sequence[float], samples: int,
                           width_px: int = 400) -> list[list[dict]]:
    """In-plane BRDF slices of surfaces as Blender renders them, one render per incidence for all of them: coaxial
    cylinders of radius 1 (axis along y, 720 smooth-shaded sides, one per surface, side by side along the axis), each
    a Principled BSDF of the surface's inputs (Principled input name -> value) over Base Color black and Subsurface
    Weight 0, lit only by a sun of irradiance 1 (angle 0.5 deg) tilted by the incidence toward +x, in a black world,
    seen straight down by an orthographic camera 2 units wide. Each pixel column sees one normal, tilted by
    beta = asin(x) in the x-z plane, so a render holds the plane of incidence's whole slice (the image-based
    measurement of Marschner et al. 1999): theta_in = |incidence - beta|, theta_out = |beta|, phi = 180 deg where the
    sun and the camera lie on opposite sides of the normal, else 0. Returns, per surface, per incidence
    {"incidence_deg", "theta_in_deg", "theta_out_deg", "phi_deg", "radiance"}: arrays over the columns with
    theta_out < 80 deg and theta_in < 89 deg; radiance = f_r cos(theta_in) (green channel)."""
    bpy = _bpy()
    n = len(surfaces)
    length = 2.0 * _SLICE_ROWS_PX / width_px  # world units per cylinder: 8 pixel rows
    angles = np.linspace(0.0, 2.0 * np.pi, _SLICE_SIDES, endpoint=False)
    x = pixel_centres_x(2.0, width_px)
    beta = np.degrees(np.arcsin(np.clip(x, -1.0, 1.0)))
    images = []
    for incidence in incidences_deg:
        scene = reset_scene()
        set_world(scene, strength=0.0)
        for k, inputs in enumerate(surfaces):
            y0 = (k - n / 2) * length
            mesh = bpy.data.meshes.new(f"Cylinder{k}")
            verts = [(float(np.cos(a)), y, float(np.sin(a))) for y in (y0, y0 + length) for a in angles]
            sides = _SLICE_SIDES
            faces = [(i, (i + 1) % sides, sides + (i + 1) % sides, sides + i) for i in range(sides)]
            mesh.from_pydata(verts, [], faces)
            mesh.update()
            for polygon in mesh.polygons:
                polygon.use_smooth = True
            cylinder = bpy.data.objects.new(f"Cylinder{k}", mesh)
            scene.collection.objects.link(cylinder)
            assign(cylinder, surface_only_material(f"Surface{k}", inputs))
        add_top_camera(scene, ortho_scale=2.0, width=width_px, height=n * _SLICE_ROWS_PX, z=5.0)
        sun = add_sun(scene, strength=1.0, angle=float(np.radians(0.5)))
        sun.rotation_euler = (0.0, float(np.radians(incidence)), 0.0)
        images.append(render(scene, samples=samples) if engine == "cycles" else render_eevee(scene, samples))
    slices = []
    for k in range(n):
        # Image row 0 is the top (+y): surface k's rows count from the bottom.
        top = (n - 1 - k) * _SLICE_ROWS_PX
        per_surface = []
        for incidence, img in zip(incidences_deg, images, strict=True):
            radiance = img[top + _SLICE_EDGE_PX : top + _SLICE_ROWS_PX - _SLICE_EDGE_PX, :, 1].mean(axis=0)
            theta_in, theta_out = np.abs(incidence - beta), np.abs(beta)
            phi = np.where((incidence - beta) * beta > 0.0, 180.0, 0.0)
            keep = (theta_out < 80.0) & (theta_in < 89.0)
            per_surface.append({"incidence_deg": float(incidence), "theta_in_deg": theta_in[keep],
                                "theta_out_deg": theta_out[keep], "phi_deg": phi[keep], "radiance": radiance[keep]})
        slices.append(per_surface)
    return slices


def slice_error(rendered: dict, oiliness: float, surface: str) -> tuple[float, float]:
    """One rendered slice (``render_in_plane_slices``) against the surface model's (``spectral_skin.surface_brdf`` times
    cos theta_in, the radiance under a sun of irradiance 1): (RMS difference over the slice / the model's peak, the
    rendered peak / the model's)."""
    import spectral_skin

    model = spectral_skin.surface_brdf(rendered["theta_in_deg"], rendered["theta_out_deg"], rendered["phi_deg"],
                                       oiliness=oiliness, surface=surface)
    model = model * np.cos(np.radians(rendered["theta_in_deg"]))
    peak = float(model.max())
    return float(np.sqrt(np.mean((rendered["radiance"] - model) ** 2)) / peak), float(rendered["radiance"].max() / peak)


def pixel_centres_x(ortho_scale: float, width: int, center_x: float = 0.0) -> np.ndarray:
    """World x (m) of each image column's pixel centre for add_top_camera's camera."""
    return center_x + ((np.arange(width) + 0.5) / width - 0.5) * ortho_scale


def half_shadow_scene(scene, material, ortho_mm: float, width: int, height: int, occluder_mm: float = 1.5):
    """The half-shadow edge scene (docs/blender-render-tests.md): a thick slab with `material` under a sun of irradiance 1 W/m^2
    from straight above, a black world, and a black half-plane `occluder_mm` above the slab over x > 0 that casts a
    hard shadow but is invisible to the camera; an orthographic top camera `ortho_mm` wide. Returns the x (mm) of the
    image columns' centres."""
    set_world(scene, strength=0.0, color=(0.0, 0.0, 0.0))
    slab = add_slab()
    assign(slab, material)
    occluder = add_plane("Occluder", 0.0, 1.0, -1.0, 1.0, z=occluder_mm * MM)
    assign(occluder, black_material())
    occluder.visible_camera = False  # casts the shadow, but camera rays pass through
    add_sun(scene, strength=1.0, angle=0.0)  # irradiance 1 W/m^2: piL = A on a lit Lambertian of albedo A
    ortho = ortho_mm * MM
    add_top_camera(scene, ortho_scale=ortho, width=width, height=height)
    return pixel_centres_x(ortho, width) / MM


def shadow_edge_scene(scene, material, ortho_mm: float, width: int, height: int, occluder_mm: float = 1.5):
    """half_shadow_scene with the slab and the occluder sized to the view, which can be metres wide (the scene-effects
    measurement and test, docs/scene-effects.md): a slab 4 times the view wide (at least 1 m), so no pixel sees its
    edges."""
    size = max(1.0, 4.0 * ortho_mm * MM)
    set_world(scene, strength=0.0, color=(0.0, 0.0, 0.0))
    slab = add_box("Slab", -size / 2, size / 2, -size / 2, size / 2, -0.2, 0.0)
    assign(slab, material)
    occluder = add_plane("Occluder", 0.0, size, -size, size, z=occluder_mm * MM)
    assign(occluder, black_material())
    occluder.visible_camera = False  # casts the shadow, but camera rays pass through
    add_sun(scene, strength=1.0, angle=0.0)
    add_top_camera(scene, ortho_scale=ortho_mm * MM, width=width, height=height)


HEAD_WIDTH_M = 0.2  # head_scene's object: Suzanne scaled to this width (a head)


def head_scene(scene, material, distance_m: float, width: int, height: int, shape: str = "SPHERE",
               lens_mm: float = 50.0):
    """A head-sized object seen from ``distance_m`` (camera to the object's centre), at the origin, with
    ``material``: ``shape`` "SPHERE", a closed UV sphere HEAD_WIDTH_M across (64 x 32 segments, with its UV map), or
    "SUZANNE", Blender's monkey head (an open mesh with thin ears, with her UV map) scaled to HEAD_WIDTH_M wide with
    one level of subdivision, facing -y; both smooth shaded. A perspective camera on the -y axis looks at it
    (``lens_mm`` on a 36 mm sensor); a sun from the front left above with irradiance pi W/m^2 (a white Lambertian
    surface facing it renders 1.0) and no angular size (hard shadows, where subsurface scattering shows), a dim white
    world (0.1) and a transparent film (alpha = the object's coverage). Returns the object."""
    bpy = _bpy()
    from mathutils import Vector

    set_world(scene, strength=0.1)
    scene.render.film_transparent = True
    if shape == "SPHERE":
        bpy.ops.mesh.primitive_uv_sphere_add(radius=HEAD_WIDTH_M / 2, segments=64, ring_count=32, calc_uvs=True)
        head = bpy.context.active_object
    elif shape == "SUZANNE":
        bpy.ops.mesh.primitive_monkey_add(size=1.0, calc_uvs=True)
        head = bpy.context.active_object
        head.scale = [HEAD_WIDTH_M / max(head.dimensions)] * 3
        subdivision = head.modifiers.new("Subdivision", "SUBSURF")
        subdivision.levels = subdivision.render_levels = 1
    else:
        raise ValueError(f"shape must be SPHERE or SUZANNE; got {shape!r}")
    head.name = "Head"
    head.data.polygons.foreach_set("use_smooth", [True] * len(head.data.polygons))
    assign(head, material)
    sun = add_sun(scene, strength=math.pi)
    sun.rotation_mode = "QUATERNION"
    sun.rotation_quaternion = Vector((-0.6, -1.0, 0.8)).to_track_quat("Z", "Y")  # +z towards the sun
    data = bpy.data.cameras.new("Camera")
    data.lens, data.sensor_width, data.sensor_fit = lens_mm, 36.0, "AUTO"
    data.clip_start, data.clip_end = min(0.01, distance_m / 10), 2.0 * distance_m + 1.0
    camera = bpy.data.objects.new("Camera", data)
    camera.location = (0.0, -distance_m, 0.0)
    camera.rotation_euler = (math.pi / 2, 0.0, 0.0)  # -z (the view axis) onto +y
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.render.resolution_x, scene.render.resolution_y = width, height
    bpy.context.view_layer.update()  # the objects' world matrices, for what reads them next
    return head


def render_edge(scene, material, ortho_mm: float, width: int, height: int, samples: int, seed: int = 1):
    """Cycles render of half_shadow_scene: returns (x in mm, piL(x)/E as (width, 3), rows averaged). Pixel-centre
    sampling (filter width 0.01 px); the EXR holds radiance L and the sun gives E = 1 W/m^2, so piL/E = pi * L."""
    x_mm = half_shadow_scene(scene, material, ortho_mm, width, height)
    img = render(scene, samples=samples, filter_width=0.01, seed=seed)
    return x_mm, math.pi * img.mean(axis=0)


def fit_burley_edge(x_mm: np.ndarray, measured: np.ndarray, d_lo_mm: float, d_hi_mm: float) -> tuple[float, float, float]:
    """Least-squares fit of scale * BurleyEdge(x; d) to one channel's rendered edge (both the scale, i.e. the rendered
    flat albedo, and the Burley length d free): golden-section search on log d in [d_lo_mm, d_hi_mm], the scale
    solved linearly for each d. Returns (d_mm, scale, rms residual / scale)."""
    measured = np.asarray(measured, dtype=np.float64)

    def solve(log_d: float) -> tuple[float, float]:
        shape = burley_edge_response(x_mm, math.exp(log_d), 1.0)
        scale = float(shape @ measured / (shape @ shape))
        return float(np.mean((measured - scale * shape) ** 2)), scale

    a, b = math.log(d_lo_mm), math.log(d_hi_mm)
    ratio = (math.sqrt(5) - 1) / 2
    c, d = b - ratio * (b - a), a + ratio * (b - a)
    fc, fd = solve(c)[0], solve(d)[0]
    while b - a > 1e-4:
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - ratio * (b - a)
            fc = solve(c)[0]
        else:
            a, c, fc = c, d, fd
            d = a + ratio * (b - a)
            fd = solve(d)[0]
    log_d = 0.5 * (a + b)
    mse, scale = solve(log_d)
    return math.exp(log_d), scale, math.sqrt(mse) / scale


# ---------------------------------------------------------------------------------------------------------------
# Reference models of the Cycles Christensen-Burley BSSRDF (docs/blender-principled.md, Subsurface Radius and
# Subsurface Scale; Edge and spot renders)

BURLEY_CDF_16D = 0.996379  # Cycles truncates the Burley profile at r = 16 d and renormalises by CDF(16 d)


def burley_edge_fraction(x: np.ndarray, d: float, n: int = 4000) -> np.ndarray:
    """g(x): the fraction of the (truncated, renormalised) Cycles Burley profile of length d beyond a straight line
    at distance x >= 0 from the entry point:

        g(x) = int_x^{16 d} (e^{-r/d} + e^{-r/3d}) / (8 pi d) * 2 acos(x / r) dr / 0.996379.

    Gauss-Legendre quadrature on [x, 16 d] after the substitution r = x + t^2 (removes the sqrt singularity of
    acos(x/r) at r = x), split into panels for the exponential decay.
    """
    x = np.atleast_1d(np.abs(np.asarray(x, dtype=np.float64)))
    rmax = 16.0 * d
    nodes, weights = np.polynomial.legendre.leggauss(64)
    out = np.zeros_like(x)
    panels = max(1, n // 64)
    for i, xi in enumerate(x):
        if xi >= rmax:
            continue
        tmax = math.sqrt(rmax - xi)
        edges = np.linspace(0.0, tmax, panels + 1)
        a = edges[:-1, None]
        b = edges[1:, None]
        t = 0.5 * (b - a) * nodes[None, :] + 0.5 * (a + b)
        w = 0.5 * (b - a) * weights[None, :]
        r = xi + t * t
        f = (np.exp(-r / d) + np.exp(-r / (3 * d))) / (8 * math.pi * d) * 2.0 * np.arccos(np.clip(xi / r, -1, 1))
        out[i] = np.sum(f * 2.0 * t * w) / BURLEY_CDF_16D
    return out


def burley_edge_response(x: np.ndarray, d: float, albedo: float) -> np.ndarray:
    """piL(x)/E for a half-plane illumination lit on x < 0: A [1 - g(|x|)] on the lit side, A g(x) on the dark side."""
    x = np.asarray(x, dtype=np.float64)
    g = burley_edge_fraction(x, d)
    return np.where(x < 0, albedo * (1.0 - g), albedo * g)


def profile_edge_fraction(x: np.ndarray, radii: np.ndarray, profile: np.ndarray) -> tuple[np.ndarray, float]:
    """Edge fraction of a tabulated radial profile R(r) (per unit area): G(x) = int_x^inf R(r) 2 r acos(x/r) dr /
    int_0^inf R(r) 2 pi r dr, by log-log interpolation of R on a fine grid; returns (G(x), total int R 2 pi r dr)."""
    radii = np.asarray(radii, dtype=np.float64)
    profile = np.asarray(profile, dtype=np.float64)
    keep = profile > 0
    lr, lp = np.log(radii[keep]), np.log(profile[keep])
    # fine log grid over the tabulated range, plus the near-0 part by extrapolating R ~ constant * r^slope
    rf = np.exp(np.linspace(lr[0], lr[-1], 20000))
    pf = np.exp(np.interp(np.log(rf), lr, lp))
    slope0 = (lp[1] - lp[0]) / (lr[1] - lr[0])
    total = _trapezoid(pf * 2 * math.pi * rf, rf)
    if slope0 > -2:  # add int_0^{r0} R 2 pi r dr for R = R0 (r/r0)^slope0
        total += 2 * math.pi * pf[0] * rf[0] ** 2 / (slope0 + 2)
    x = np.atleast_1d(np.abs(np.asarray(x, dtype=np.float64)))
    out = np.empty_like(x)
    for i, xi in enumerate(x):
        if xi <= rf[0]:
            # the whole profile beyond the line at ~0: half of it
            out[i] = 0.5
            continue
        if xi >= rf[-1]:
            out[i] = 0.0
            continue
        # substitution r = xi + t^2 on [xi, r_max]
        tmax = math.sqrt(rf[-1] - xi)
        t = np.linspace(0, tmax, 40001) ** 2 / tmax  # cluster near 0
        r = xi + t * t
        pr = np.exp(np.interp(np.log(r), lr, lp))
        f = pr * 2 * r * np.arccos(np.clip(xi / r, -1, 1)) * 2 * t
        out[i] = _trapezoid(f, t) / total
    return out, total


def write_json_atomically(path, data) -> None:
    """Write ``data`` as indented JSON to ``path`` through a temporary file renamed over it (never half-written)."""
    import json
    from pathlib import Path

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    os.replace(tmp, path)
