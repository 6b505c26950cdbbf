"""Runs inside Blender (blender -b --python-exit-code 1 --python render_cycles.py -- DIR).

Imports photomat's exported pbr tile (DIR/export/tile.gltf, see run-cycles-render-test) with
Blender's glTF importer, renders it with Cycles under lights of the capture and compares each
render with `photomat relight --method pbr` at the same light (DIR/relit_INDEX.exr) on a crop.

Conventions (photomat's core/microfacet_brdf.h against Blender's):
  - view: an orthographic camera looking along -z at the tile, which the importer lays on the
    ground (x right, y away = image up), one render pixel per texel; image textures sampled
    'Closest' and a 1-pixel box filter, so that each render pixel sees exactly its texel, as
    photomat's relighting does;
  - light: photomat's unit vector l towards the light (x right, y up in the image, z towards the
    camera) is the same vector in Blender's frame; a sun lamp (angle 0, a distant light) whose
    local +z points along l;
  - intensity: photomat's radiance is pi * BRDF * cos * I with I = 1 for the capture's lights (a
    white Lambertian surface facing the light has radiance 1); Blender's sun strength is the
    irradiance E in W/m^2, radiance = BRDF * cos * E, so strength = pi * I = pi;
  - colour: the render is written as linear float EXR (the 'Standard' view transform, no look,
    exposure 0), as photomat's relit EXR is linear;
  - nothing else in the scene (a black world, no other objects), so the image is the direct light
    of the sun alone, which Cycles samples without noise for a delta light: few samples suffice,
    no denoiser.

What cannot match exactly: Blender 3.4's Principled BSDF is not photomat's model. Its diffuse
lobe is Disney's (Burley) with a roughness-dependent retro-reflection, not Lambert's; it adds
the specular lobe on top of the diffuse instead of glTF's fresnel_mix (1 - F) weighting; its GGX
masking-shadowing is the separable Smith form (photomat: height-correlated); and the exported
textures are 8-bit sRGB base colour and 16-bit roughness and specular. The distribution is set
to plain 'GGX' (Blender's default multiscatter GGX adds energy photomat's single-scattering model
does not have). The mean differences are therefore measured and bounded, not zero.
"""
import json
import math
import os
import sys

import bpy
import mathutils
import numpy

# Debian 12's Blender 3.4.1 glTF add-on still uses numpy.bool, which Debian's numpy 1.24 removed
# (see check_imports.py): restore the alias so the importer runs at all.
if "bool" not in numpy.__dict__:
    numpy.bool = bool

work = sys.argv[sys.argv.index("--") + 1]
failures = []

# Mean |Cycles - photomat| over the crop and the three channels, relative to photomat's mean
# there, per light slant (the two lights run-cycles-render-test relights).
# Measured (Debian 12, Blender 3.4.1, generate --ggx bumps 48x40 seed 3): slant 30: 0.0559
# (signed +0.0559, correlation 0.9989), slant 60: 0.0686 (signed +0.0663, correlation 0.9941);
# Cycles is brighter: Burley's retro-reflection and the diffuse without the (1 - F) weight.
# Bounds = 1.3 x measured.
BOUNDS = {30: 0.073, 60: 0.089}
CROP_BORDER = 4  # texels left out at each edge (the fit's and the normal map's border pixels)


def check(condition, what):
    print(("ok   " if condition else "FAIL ") + what)
    if not condition:
        failures.append(what)


def image_pixels(image):
    """A Blender image as a (rows, columns, 4) float array, row 0 at the top."""
    width, height = image.size
    pixels = numpy.array(image.pixels[:], dtype=numpy.float64).reshape(height, width, 4)
    return pixels[::-1]  # Blender stores the bottom row first


def build_scene(width, height):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.join(work, "export", "tile.gltf"))
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    check(len(meshes) == 1, f"one imported mesh (got {len(meshes)})")
    tile = meshes[0]
    material = tile.active_material
    for node in material.node_tree.nodes:
        if node.type == "TEX_IMAGE":
            node.interpolation = "Closest"
        if node.type == "BSDF_PRINCIPLED":
            node.distribution = "GGX"
    corners = [tile.matrix_world @ mathutils.Vector(c) for c in tile.bound_box]
    low = mathutils.Vector([min(c[i] for c in corners) for i in range(3)])
    high = mathutils.Vector([max(c[i] for c in corners) for i in range(3)])

    scene = bpy.context.scene
    camera_data = bpy.data.cameras.new("camera")
    camera_data.type = "ORTHO"
    camera_data.ortho_scale = max(high.x - low.x, high.y - low.y)
    camera = bpy.data.objects.new("camera", camera_data)
    camera.location = ((low.x + high.x) / 2, (low.y + high.y) / 2, high.z + 1.0)
    camera.rotation_euler = (0.0, 0.0, 0.0)  # looks along -z, image up = +y
    scene.collection.objects.link(camera)
    scene.camera = camera

    world = bpy.data.worlds.new("black")
    world.use_nodes = False
    world.color = (0.0, 0.0, 0.0)
    scene.world = world

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 4
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.filter_type = "BOX"
    scene.cycles.filter_width = 1.0
    scene.cycles.seed = 1
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.color_mode = "RGBA"

    sun_data = bpy.data.lights.new("sun", type="SUN")
    sun_data.angle = 0.0
    sun_data.energy = math.pi  # the sun's strength E = pi I, I = 1 (module docstring)
    sun = bpy.data.objects.new("sun", sun_data)
    scene.collection.objects.link(sun)
    return scene, sun


def main():
    with open(os.path.join(work, "ggx", "manifest.json")) as f:
        capture = json.load(f)
    with open(os.path.join(work, "render.json")) as f:
        indices = json.load(f)["lights"]
    with open(os.path.join(work, "export", "export.json")) as f:
        exported = json.load(f)
    width, height = exported["width"], exported["height"]
    scene, sun = build_scene(width, height)
    for index in indices:
        entry = capture["images"][index]
        light = mathutils.Vector(entry["light"]).normalized()
        sun.rotation_euler = light.to_track_quat("Z", "Y").to_euler()
        path = os.path.join(work, f"cycles_{index}.exr")
        scene.render.filepath = path
        bpy.ops.render.render(write_still=True)
        rendered = image_pixels(bpy.data.images.load(path))[..., :3]
        relit_image = bpy.data.images.load(os.path.join(work, f"relit_{index}.exr"))
        relit_image.colorspace_settings.name = "Non-Color"
        relit = image_pixels(relit_image)[..., :3]
        check(rendered.shape == relit.shape, f"light {index}: sizes {rendered.shape} {relit.shape}")
        if rendered.shape != relit.shape:
            continue
        b = CROP_BORDER
        a, r = rendered[b:-b, b:-b], relit[b:-b, b:-b]
        difference = numpy.abs(a - r).mean() / r.mean()
        signed = (a - r).mean() / r.mean()
        correlation = numpy.corrcoef(a.ravel(), r.ravel())[0, 1]
        slant = round(entry["slant_deg"])
        print(f"light {index} (slant {entry['slant_deg']:.1f}, tilt {entry['tilt_deg']:.1f}): "
              f"photomat mean {r.mean():.5f}, Cycles mean {a.mean():.5f}, mean |difference| / mean "
              f"{difference:.5f}, mean signed difference / mean {signed:+.5f}, correlation "
              f"{correlation:.5f}")
        bound = BOUNDS.get(slant)
        if bound is not None:
            check(difference < bound, f"light {index}: mean |Cycles - photomat| / mean "
                  f"{difference:.4f} < {bound}")
    if failures:
        raise SystemExit(f"{len(failures)} Cycles render check(s) failed: {failures}")
    print("all Cycles render checks passed")


main()
