"""Live mode through the add-on's one Apply path (apply.apply_skins, as the panel's Apply in Live mode): the "Spectral
Skin" node group wired into the tagged Principled BSDF renders, in Cycles (CPU, Burley, a thick flat slab under a
white world, Specular IOR Level 0 from oiliness 0: tests/blender/test_renders.py's setup), the core's albedo

(a) for the panel's constants;
(b) for a haemoglobin keyed on the group node's input socket, at two frames, with no Apply in between;
(c) per texel of a small parameter texture, the same as the Baked material and as ``spectral_skin.maps``: a
    four-channel parameter EXR (the core's reading, packed) and a painted (generated) haemoglobin image, which the
    group reads itself.

Bound: the shader table's Base Color error (docs/shader-table.md: 0.450 % for the default 33 x 9 x 17 Burley table)
plus 0.2 % for the render (test_renders.py's Burley tolerance). Run: python -m pytest tests/blender/test_live_mode.py -s
"""

from __future__ import annotations

import functools
import pathlib

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
oiio = pytest.importorskip("OpenImageIO")
spectral_skin = pytest.importorskip("spectral_skin")

import blender_scenes  # noqa: E402
from blender_scenes import add_slab, add_top_camera, assign, eevee_engine_id, render, set_world  # noqa: E402
from live_scene import BURLEY_SPP, apply_materials, centre, check, core_albedo, skin_material, slab_scene  # noqa: E402

from blender_addon import nodes as addon_nodes  # noqa: E402

TEXEL_SPP = 1024  # test_renders.py: the 4-texel image
TEXEL_SPAN_M = 0.0256  # test_renders.py: the texels' widest span, narrower where a radius would cover < 1 pixel


EEVEE_STEP = 1.0 / 1024  # EEVEE's colour step in these renders (test_live_in_eevee_renders_as_baked)


def test_live_constants_render_the_cores_albedo(addon, tmp_path):
    scene = blender_scenes.reset_scene()
    material = skin_material("Skin", "LIVE", melanin=0.05, hemoglobin=0.02)
    slab_scene(material)
    plan = apply_materials(scene, material)[0]
    assert plan.live is not None and plan.live["table"] is not None
    tree = material.node_tree
    (group_node,) = addon_nodes.tagged_nodes(tree, "live")
    principled = addon_nodes.tagged_nodes(tree, "principled")[0]
    for output in ("Base Color", "Subsurface Radius", "Specular IOR Level"):
        assert principled.inputs[output].links[0].from_node == group_node, output
    for image in group_node.node_tree.nodes:
        if image.type == "TEX_IMAGE":
            assert image.image.packed_file is not None and image.image.colorspace_settings.name == "Non-Color"
    check("constants", centre(render(scene, samples=BURLEY_SPP)), core_albedo(0.05, 0.7, 0.02))
    # The table travels packed in the .blend: saved, the table's temporary arrays gone, reopened, the same render.
    blend = tmp_path / "live.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    scene, material = bpy.context.scene, bpy.data.materials["Skin"]
    tree = material.node_tree
    principled = addon_nodes.tagged_nodes(tree, "principled")[0]
    check("constants, reopened", centre(render(scene, samples=BURLEY_SPP)), core_albedo(0.05, 0.7, 0.02))
    # Apply again: the table is reused from the blend file, not recomputed; Baked then removes the live nodes.
    assert apply_materials(scene, material)[0].live["table"] is None
    material.spectral_skin.mode = "BAKED"
    apply_materials(scene, material)
    assert not addon_nodes.tagged_nodes(tree, "live")
    assert not principled.inputs["Base Color"].is_linked


def test_live_keyed_haemoglobin_renders_the_cores_albedo_at_two_frames(addon):
    scene = blender_scenes.reset_scene()
    material = skin_material("Skin", "LIVE", melanin=0.02)
    slab_scene(material)
    apply_materials(scene, material)
    (group_node,) = addon_nodes.tagged_nodes(material.node_tree, "live")
    socket = group_node.inputs["Hemoglobin"]
    # How an artist keys haemoglobin: hover the group node's Hemoglobin field and press I (this, from a script).
    for frame, value in ((1, 0.003), (10, 0.06)):
        socket.default_value = value
        socket.keyframe_insert("default_value", frame=frame)
    for frame, value in ((1, 0.003), (10, 0.06)):
        scene.frame_set(frame)
        check(f"keyed haemoglobin {value} at frame {frame}", centre(render(scene, samples=BURLEY_SPP)),
               core_albedo(0.02, 0.7, value))


def _params() -> np.ndarray:
    """A 4 x 1 parameter row (test_renders.py's texels, oiliness 0)."""
    params = np.zeros((1, 4, 4), dtype=np.float32)
    params[0, :, 0] = [0.005, 0.05, 0.15, 0.35]
    params[0, :, 1] = [0.3, 0.7, 0.5, 0.9]
    params[0, :, 2] = [0.005, 0.02, 0.05, 0.1]
    return params


def _painted(hemoglobin: np.ndarray, image=None):
    """A float image Blender holds in memory only (as after painting), one row of haemoglobin values; or those values
    painted over ``image``."""
    if image is None:
        image = bpy.data.images.new("Painted", width=len(hemoglobin), height=1, float_buffer=True)
    rgba = np.ones((1, len(hemoglobin), 4), dtype=np.float32)
    rgba[..., :3] = hemoglobin[None, :, None]
    image.pixels.foreach_set(rgba.ravel())
    image.update()
    return image


@functools.cache
def _texel_span_m() -> float:
    """How wide the 4 texels of _params() lie on the slab: TEXEL_SPAN_M, or less so that each texel's smallest Burley
    radius covers a pixel of the 64-pixel image (blender_scenes.span_resolving)."""
    radius_mm = spectral_skin.maps(_params(), method="burley", blender=tuple(bpy.app.version))["radius"]
    return blender_scenes.span_resolving(radius_mm, 64, TEXEL_SPAN_M)


def _uv_slab():
    """The slab with a UV map putting the 4 texels across _texel_span_m() of its top (u = x / span + 1/2)."""
    slab = add_slab()
    mesh = slab.data
    uv = mesh.uv_layers.new(name="UVMap")
    span_m = _texel_span_m()
    for loop in mesh.loops:
        x, y, _ = mesh.vertices[loop.vertex_index].co
        uv.data[loop.index].uv = (x / span_m + 0.5, y / span_m + 0.5)
    return slab


def _two_tile_slab():
    """The slab (1 m wide, 0.2 m thick, top at z = 0) with its top split so that the middle _texel_span_m() square is two
    faces, one per UDIM tile: u = 2 (x / span + 1/2) from 0 to 1 (tile 1001) and from 1 to 2 (tile 1002), v = y / span
    + 1/2 from 0 to 1, two texels of a 2-texel-wide tile each. (Cycles loads only the tiles the mesh's faces lie in, in
    a background render: one face spanning both tiles, with its corners far outside, would load neither.)"""
    h, s, depth = 0.5, _texel_span_m(), 0.2
    xs, ys = (-h, -s / 2, 0.0, s / 2, h), (-h, -s / 2, s / 2, h)

    def top(i: int, j: int) -> int:
        return j * len(xs) + i

    verts = [(x, y, 0.0) for y in ys for x in xs]
    b = len(verts)
    verts += [(-h, -h, -depth), (h, -h, -depth), (-h, h, -depth), (h, h, -depth)]  # b00, b10, b01, b11
    faces = [(top(i, j), top(i + 1, j), top(i + 1, j + 1), top(i, j + 1))
             for j in range(len(ys) - 1) for i in range(len(xs) - 1)]
    faces += [
        (b, b + 2, b + 3, b + 1),  # bottom (-z)
        (b, b + 1, *[top(i, 0) for i in reversed(range(len(xs)))]),  # -y
        (b + 2, *[top(i, len(ys) - 1) for i in range(len(xs))], b + 3),  # +y
        (b, *[top(0, j) for j in range(len(ys))], b + 2),  # -x
        (b + 1, b + 3, *[top(len(xs) - 1, j) for j in reversed(range(len(ys)))]),  # +x
    ]
    mesh = bpy.data.meshes.new("Slab")
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    slab = bpy.data.objects.new("Slab", mesh)
    bpy.context.scene.collection.objects.link(slab)
    uv = mesh.uv_layers.new(name="UVMap")
    for loop in mesh.loops:
        x, y, _ = mesh.vertices[loop.vertex_index].co
        uv.data[loop.index].uv = (2 * (x / s + 0.5), y / s + 0.5)
    return slab


def _closest(material) -> None:
    """Closest lookups (the add-on's are Linear), so that each texel's interior is that texel's alone (Baked: its
    outputs; Live: its parameters): test_renders.py's per-texel setup."""
    for node in material.node_tree.nodes:
        if node.type == "TEX_IMAGE":
            node.interpolation = "Closest"


def _texels(scene, material) -> np.ndarray:
    slab = bpy.data.objects["Slab"]
    assign(slab, material)
    img = render(scene, samples=TEXEL_SPP)
    return np.array([img[2:-2, k * 16 + 3 : (k + 1) * 16 - 3].reshape(-1, 3).mean(axis=0) for k in range(4)])


@pytest.mark.parametrize("source", ["parameter exr", "painted haemoglobin", "png haemoglobin"])
def test_live_texture_matches_baked_and_the_core_per_texel(addon, tmp_path, source):
    scene = blender_scenes.reset_scene()
    set_world(scene, strength=1.0)
    _uv_slab()
    add_top_camera(scene, ortho_scale=_texel_span_m(), width=64, height=16)
    params = _params()
    if source == "parameter exr":
        path = tmp_path / "params.exr"
        spec = oiio.ImageSpec(4, 1, 4, "float")
        spec.channelnames = ("melanin", "melanin_blend", "hemoglobin", "oiliness")
        out = oiio.ImageOutput.create(str(path))
        assert out is not None and out.open(str(path), spec), oiio.geterror()
        assert out.write_image(params), out.geterror()
        out.close()
        image = bpy.data.images.load(str(path))
    elif source == "png haemoglobin":
        # 8-bit greyscale: 0..255 onto [0, 0.1] (the core's reading; Blender's goes through the group's Math node).
        params[0, :, 0], params[0, :, 1] = 0.05, 0.7
        grey = np.array([[13, 51, 128, 255]], dtype=np.uint8)
        params[0, :, 2] = grey[0] / 255.0 * 0.1
        path = tmp_path / "hemoglobin.png"
        out = oiio.ImageOutput.create(str(path))
        assert out is not None and out.open(str(path), oiio.ImageSpec(4, 1, 1, "uint8")), oiio.geterror()
        assert out.write_image(grey[:, :, None]), out.geterror()
        out.close()
        image = bpy.data.images.load(str(path))
    else:
        params[0, :, 0], params[0, :, 1] = 0.05, 0.7
        image = _painted(params[0, :, 2])
    materials = []
    for mode in ("LIVE", "BAKED"):
        material = skin_material(mode.title(), mode, melanin=0.05, melanin_blend=0.7)
        if source == "parameter exr":
            material.spectral_skin.params_map = image
        else:
            material.spectral_skin.hemoglobin_map = image
        material.spectral_skin.output_dir = str(tmp_path / "maps")
        materials.append(material)
    apply_materials(scene, *materials)
    live_material, baked_material = materials
    assert addon_nodes.tagged_nodes(live_material.node_tree, "live hemoglobin")
    assert not addon_nodes.tagged_nodes(baked_material.node_tree, "live")
    for material in materials:
        _closest(material)
    # Burley's Base Color is the albedo (test_renders.py).
    core = np.asarray(spectral_skin.maps(params, blender=tuple(bpy.app.version), engine="cycles",
                                         method="burley")["albedo"], dtype=np.float64)[0]
    live, baked = _texels(scene, live_material), _texels(scene, baked_material)
    worst = {"live vs core": 0.0, "live vs baked": 0.0, "baked vs core": 0.0}
    for k in range(4):
        worst["live vs core"] = max(worst["live vs core"], check(f"{source} texel {k} live", live[k], core[k]))
        worst["baked vs core"] = max(worst["baked vs core"], check(f"{source} texel {k} baked", baked[k], core[k]))
        worst["live vs baked"] = max(worst["live vs baked"],
                                     check(f"{source} texel {k} live vs baked", live[k], baked[k]))
    print(f"[live] {source}: worst |rel.err| " + ", ".join(f"{k} {v * 100:.3f} %" for k, v in worst.items()))
    if source == "painted haemoglobin":
        # Paint again, no Apply: the live material follows (the panel's acceptance path: paint, see).
        params[0, :, 2] = params[0, ::-1, 2]
        _painted(params[0, :, 2], image)
        core = np.asarray(spectral_skin.maps(params, blender=tuple(bpy.app.version), engine="cycles",
                                             method="burley")["albedo"], dtype=np.float64)[0]
        repainted = _texels(scene, live_material)
        for k in range(4):
            check(f"repainted texel {k} live, no Apply", repainted[k], core[k])


def _write_exr(path: pathlib.Path, pixels: np.ndarray, channels: tuple[str, ...]) -> None:
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, "float")
    spec.channelnames = channels
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec), oiio.geterror()
    assert out.write_image(np.ascontiguousarray(pixels, dtype=np.float32)), out.geterror()
    out.close()


@pytest.mark.parametrize("source", ["parameter exr tile set", "png haemoglobin tile set"])
def test_live_reads_a_udim_tile_set_as_baked_and_the_core_per_texel(addon, tmp_path, source):
    """A UDIM tile set of two tiles (1001, 1002: two texels each) under a UV map across both: Live mode reads it
    (the four-channel parameter EXRs as a packed tiled float copy of the core's reading; 8-bit PNG tiles directly),
    and renders per texel as the Baked material (tiled textures) and the core."""
    scene = blender_scenes.reset_scene()
    set_world(scene, strength=1.0)
    _two_tile_slab()
    add_top_camera(scene, ortho_scale=_texel_span_m(), width=64, height=16)
    params = _params()
    if source == "parameter exr tile set":
        for k, tile in enumerate((1001, 1002)):
            _write_exr(tmp_path / f"params.{tile}.exr", params[:, 2 * k:2 * k + 2],
                       ("melanin", "melanin_blend", "hemoglobin", "oiliness"))
        image = bpy.data.images.load(str(tmp_path / "params.1001.exr"))
    else:
        params[0, :, 0], params[0, :, 1] = 0.05, 0.7
        grey = np.array([[13, 51, 128, 255]], dtype=np.uint8)
        params[0, :, 2] = grey[0] / 255.0 * 0.1
        for k, tile in enumerate((1001, 1002)):
            path = tmp_path / f"hemoglobin.{tile}.png"
            out = oiio.ImageOutput.create(str(path))
            assert out is not None and out.open(str(path), oiio.ImageSpec(2, 1, 1, "uint8")), oiio.geterror()
            assert out.write_image(np.ascontiguousarray(grey[:, 2 * k:2 * k + 2, None])), out.geterror()
            out.close()
        image = bpy.data.images.load(str(tmp_path / "hemoglobin.1001.png"))
    image.source = "TILED"
    assert sorted(t.number for t in image.tiles) == [1001, 1002]
    materials = []
    for mode in ("LIVE", "BAKED"):
        material = skin_material(mode.title(), mode, melanin=0.05, melanin_blend=0.7)
        if source == "parameter exr tile set":
            material.spectral_skin.params_map = image
        else:
            material.spectral_skin.hemoglobin_map = image
        material.spectral_skin.output_dir = str(tmp_path / "maps")
        materials.append(material)
    apply_materials(scene, *materials)
    live_material, baked_material = materials
    read = addon_nodes.tagged_nodes(live_material.node_tree, "live hemoglobin")[0].image
    assert read.source == "TILED" and sorted(t.number for t in read.tiles) == [1001, 1002]
    if source == "parameter exr tile set":
        assert read.name == "SpectralSkin Live hemoglobin" and read.packed_files, "a packed copy"
    else:
        assert read == image, "the tile set itself"
    for material in materials:
        _closest(material)
    core = np.asarray(spectral_skin.maps(params, blender=tuple(bpy.app.version), engine="cycles",
                                         method="burley")["albedo"], dtype=np.float64)[0]
    live, baked = _texels(scene, live_material), _texels(scene, baked_material)
    for k in range(4):
        check(f"{source} texel {k} live", live[k], core[k])
        check(f"{source} texel {k} baked", baked[k], core[k])
        check(f"{source} texel {k} live vs baked", live[k], baked[k])
    if source == "parameter exr tile set":
        # Saved and opened again, the packed copy's tiles are still there (nothing depends on the temporary files).
        blend = tmp_path / "live.blend"
        live_material.use_fake_user = True  # the slab has the Baked one now: keep the Live one in the file
        bpy.ops.wm.save_as_mainfile(filepath=str(blend))
        bpy.ops.wm.open_mainfile(filepath=str(blend))
        scene = bpy.context.scene
        again = _texels(scene, bpy.data.materials["Live"])
        for k in range(4):
            check(f"{source} texel {k} live, reopened", again[k], core[k])


def test_remove_restores_the_previous_shader_and_drops_the_packed_copies(addon, tmp_path):
    scene = blender_scenes.reset_scene()
    material = skin_material("Skin", "LIVE")
    if material.node_tree is None:  # Blender < 5.0
        material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    tree.links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
    path = tmp_path / "params.exr"
    spec = oiio.ImageSpec(4, 1, 4, "float")
    spec.channelnames = ("melanin", "melanin_blend", "hemoglobin", "oiliness")
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec), oiio.geterror()
    assert out.write_image(_params()), out.geterror()
    out.close()
    material.spectral_skin.params_map = bpy.data.images.load(str(path))
    apply_materials(scene, material)
    copies = [f"SpectralSkin Skin {p}" for p in ("melanin", "melanin_blend", "hemoglobin", "oiliness")]
    assert all(bpy.data.images[name].packed_file is not None for name in copies)
    assert bpy.ops.spectral_skin.remove(material="Skin") == {"FINISHED"}
    assert not addon_nodes.tagged_nodes(tree)
    assert output.inputs["Surface"].links[0].from_node == diffuse
    assert not any(name in bpy.data.images for name in copies)


@pytest.mark.skipif(tuple(bpy.app.version[:2]) < (4, 5), reason="bpy 4.2's EEVEE subsurface is not repeatable under "
                    "Mesa llvmpipe (docs/blender-render-tests.md, EEVEE edge)")
def test_live_in_eevee_renders_as_baked(addon):
    """EEVEE: the group compiles and evaluates there; Live and Baked (each for EEVEE's target) render the same slab."""
    scene = blender_scenes.reset_scene()
    scene.render.engine = eevee_engine_id()
    scene.eevee.taa_render_samples = 16
    live_material = skin_material("Live", "LIVE", melanin=0.05, hemoglobin=0.02)
    baked_material = skin_material("Baked", "BAKED", melanin=0.05, hemoglobin=0.02)
    set_world(scene, strength=1.0)
    # Two slabs side by side in one render (x < 0 live, x > 0 baked), measured 16 pixels (24 mm) from the seam.
    assign(blender_scenes.add_box("Live", -0.5, 0.0, -0.5, 0.5, -0.2, 0.0), live_material)
    assign(blender_scenes.add_box("Baked", 0.0, 0.5, -0.5, 0.5, -0.2, 0.0), baked_material)
    add_top_camera(scene, ortho_scale=0.2, width=128, height=64)
    plans = apply_materials(scene, live_material, baked_material)
    assert plans[0].live is not None and " eevee" in plans[0].live["group"]
    img = render(scene, samples=1)
    live, baked = (img[16:48, x : x + 32].reshape(-1, 3).mean(axis=0) for x in (16, 80))
    # EEVEE keeps the surface colour in its g-buffer at about 10 bits: its renders here come in steps of 1/1024
    # (0.8 % of the blue 0.12), so the two agree to the bit or one step apart (measured in 5.0 and 5.3).
    check("EEVEE live vs baked", live, baked, atol=EEVEE_STEP)
    # The group is evaluated in EEVEE: its input (haemoglobin 0.02 -> 0.06, no Apply) changes the live half as
    # applying Baked at 0.06 changes the baked one.
    (group_node,) = addon_nodes.tagged_nodes(live_material.node_tree, "live")
    group_node.inputs["Hemoglobin"].default_value = 0.06
    baked_material.spectral_skin.hemoglobin = 0.06
    apply_materials(scene, baked_material)
    img = render(scene, samples=1)
    live_high, baked_high = (img[16:48, x : x + 32].reshape(-1, 3).mean(axis=0) for x in (16, 80))
    assert np.abs(live_high / live - 1.0).max() > 0.01
    check("EEVEE live vs baked at haemoglobin 0.06", live_high, baked_high, atol=EEVEE_STEP)


def test_a_group_of_another_layout_is_rebuilt_not_reused(addon):
    """A node group left by an older add-on (another layout version, e.g. EEVEE's before it computed its own
    bilinear weights) is rebuilt at the next Apply; one of this version is reused."""
    from blender_addon import live

    scene = blender_scenes.reset_scene()
    material = skin_material("Skin", "LIVE")
    slab_scene(material)
    apply_materials(scene, material)
    (group_node,) = addon_nodes.tagged_nodes(material.node_tree, "live")
    group = group_node.node_tree
    assert apply_materials(scene, material)[0].live["table"] is None
    group[live.LAYOUT_KEY] = live.LAYOUT_VERSION - 1
    assert apply_materials(scene, material)[0].live["table"] is not None
    assert group[live.LAYOUT_KEY] == live.LAYOUT_VERSION
