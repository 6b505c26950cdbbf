"""Runs inside Blender (blender -b --python-exit-code 1 --python check_imports.py -- DIR).

Imports what photomat wrote into DIR (see run-blender-import-test) with Blender's own importers
and checks that Blender sees what photomat meant: the glTF tile's textures wired as base colour and
normal map (and a pbr tile's roughness, metallic and specular, with their colour spaces and values), per-vertex colours of the carved and reaction-diffusion meshes (glTF and PLY), and the
solid texture's OpenVDB grids. Any failed check raises, and Blender exits non-zero.
"""
import json
import os
import sys

import bpy
import numpy

# Debian 12's Blender 3.4.1 glTF add-on still uses numpy.bool, which Debian's numpy 1.24 removed
# (an incompatibility between two Debian packages, not in photomat's files): restore the alias
# so the importer runs at all.
if "bool" not in numpy.__dict__:
    numpy.bool = bool

out = sys.argv[sys.argv.index("--") + 1]
failures = []


def check(condition, what):
    print(("ok   " if condition else "FAIL ") + what)
    if not condition:
        failures.append(what)


def fresh_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def imported_meshes():
    return [o for o in bpy.context.scene.objects if o.type == "MESH"]


def linked_from(socket):
    return socket.links[0].from_node if socket.is_linked else None


def check_tile(path, width, height):
    fresh_scene()
    bpy.ops.import_scene.gltf(filepath=path)
    meshes = imported_meshes()
    check(len(meshes) == 1, f"tile.gltf: one mesh object (got {len(meshes)})")
    if not meshes:
        return
    mesh = meshes[0]
    # One pixel = 1 / width scene units; glTF's +Y up becomes Blender's +Z: the tile lies on the
    # ground (x right, y away from the viewer).
    x, y, z = mesh.dimensions
    check(abs(x - 1.0) < 1e-5 and abs(y - height / width) < 1e-5 and z < 1e-6,
          f"tile.gltf: a flat 1 x {height / width:.4f} tile on the ground (got {x}, {y}, {z})")
    check(len(mesh.data.uv_layers) >= 1, "tile.gltf: texture coordinates")
    material = mesh.active_material
    check(material is not None and material.use_nodes, "tile.gltf: a node material")
    if material is None:
        return
    displacement = material.get("displacement")
    check(displacement is not None and {"texture", "scale", "offset"} <= set(displacement.keys()),
          "tile.gltf: the height's displacement extras arrive as a material property")
    nodes = material.node_tree.nodes
    bsdf = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)
    check(bsdf is not None, "tile.gltf: a Principled BSDF")
    if bsdf is None:
        return
    base = linked_from(bsdf.inputs["Base Color"])
    check(base is not None and base.type == "TEX_IMAGE", "tile.gltf: base colour from an image")
    normal_map = linked_from(bsdf.inputs["Normal"])
    check(normal_map is not None and normal_map.type == "NORMAL_MAP", "tile.gltf: a normal map node")
    normal_image = linked_from(normal_map.inputs["Color"]) if normal_map else None
    check(normal_image is not None and normal_image.type == "TEX_IMAGE",
          "tile.gltf: the normal map reads an image")
    for label, node in (("base colour", base), ("normal", normal_image)):
        if node is None or node.image is None:
            continue
        size = tuple(node.image.size)
        check(size == (width, height), f"tile.gltf: {label} image loads at {width}x{height} (got {size})")
    if normal_image is not None and normal_image.image is not None:
        check(normal_image.image.colorspace_settings.name == "Non-Color",
              "tile.gltf: the normal image is read as non-colour data")


def image_channel(image, channel):
    """One channel of a Blender image's pixels (RGBA floats, as Blender decodes them)."""
    pixels = numpy.array(image.pixels[:], dtype=numpy.float64).reshape(-1, 4)
    return pixels[:, channel]


def load_data_image(path):
    image = bpy.data.images.load(path)
    image.colorspace_settings.name = "Non-Color"
    return image


def check_pbr_tile(folder):
    """The pbr export: glTF's metallic-roughness texture drives the Principled BSDF's roughness
    (G) and metallic (B) as non-colour data, KHR_materials_specular its Specular, the base colour
    is sRGB, and the values are photomat's maps."""
    fresh_scene()
    bpy.ops.import_scene.gltf(filepath=os.path.join(folder, "tile.gltf"))
    meshes = imported_meshes()
    check(len(meshes) == 1 and meshes[0].active_material is not None, "pbr tile: one material")
    if not meshes or meshes[0].active_material is None:
        return
    nodes = meshes[0].active_material.node_tree.nodes
    bsdf = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)
    check(bsdf is not None, "pbr tile: a Principled BSDF")
    if bsdf is None:
        return
    base = linked_from(bsdf.inputs["Base Color"])
    check(base is not None and base.type == "TEX_IMAGE" and base.image is not None and
          base.image.colorspace_settings.name == "sRGB", "pbr tile: base colour from an sRGB image")
    separate = linked_from(bsdf.inputs["Roughness"])
    check(separate is not None and separate.type == "SEPARATE_COLOR" and
          bsdf.inputs["Roughness"].links[0].from_socket.name == "Green",
          "pbr tile: roughness from the green channel of a texture")
    check(bsdf.inputs["Metallic"].is_linked and
          bsdf.inputs["Metallic"].links[0].from_socket.name == "Blue",
          "pbr tile: metallic from the blue channel")
    texture = linked_from(separate.inputs[0]) if separate is not None else None
    check(texture is not None and texture.type == "TEX_IMAGE" and texture.image is not None and
          texture.image.colorspace_settings.name == "Non-Color",
          "pbr tile: the metallic-roughness image is non-colour data")
    if texture is not None and texture.image is not None:
        roughness = load_data_image(os.path.join(folder, "roughness.png"))
        # Both images are stored with row 0 at the top: compare texel by texel.
        difference = numpy.abs(image_channel(texture.image, 1) - image_channel(roughness, 0)).max()
        check(difference < 1e-3, f"pbr tile: Blender's roughness is photomat's (max diff {difference:.2e})")
        metallic = image_channel(texture.image, 2).max()
        check(metallic == 0.0, f"pbr tile: a dielectric, metallic 0 (max {metallic})")
    specular = linked_from(bsdf.inputs["Specular"])
    check(specular is not None and specular.type == "TEX_IMAGE" and specular.image is not None and
          specular.image.colorspace_settings.name == "Non-Color",
          "pbr tile: KHR_materials_specular arrives as a non-colour Specular texture")
    if specular is not None and specular.image is not None:
        # Blender's Principled Specular s gives F0 = 0.08 s: its mean is the fit's mean F0 / 0.08.
        f0 = load_data_image(os.path.join(folder, "specular_level.png"))
        expected = image_channel(f0, 0).mean()
        got = image_channel(specular.image, 0).mean()
        check(abs(got - expected) < 0.02 * max(expected, 1e-3),
              f"pbr tile: Blender's Specular mean {got:.4f} is F0 / 0.08 = {expected:.4f}")


def colour_values(mesh):
    """Per-vertex RGB, flattened; importers store colours per vertex (PLY) or per face corner
    (glTF), so corners are gathered back onto their vertices."""
    attributes = mesh.data.color_attributes
    if len(attributes) == 0:
        return None
    attribute = attributes[0]
    if attribute.domain == "CORNER":
        per_vertex = {}
        for loop in mesh.data.loops:
            per_vertex[loop.vertex_index] = attribute.data[loop.index].color[:3]
        colours = [per_vertex[i] for i in sorted(per_vertex)]
    else:
        colours = [item.color[:3] for item in attribute.data]
    return [v for colour in colours for v in colour]


def read_vertex_values(path):
    """photomat's vertex_values.csv: a header of channel names, then one row per vertex."""
    with open(path) as f:
        rows = [line.strip().split(",") for line in f if line.strip()]
    return [[float(v) for v in row[:3]] for row in rows[1:]]


def check_coloured_mesh(label, vertices_expected, load, truth=None):
    fresh_scene()
    load()
    meshes = imported_meshes()
    check(len(meshes) == 1, f"{label}: one mesh object (got {len(meshes)})")
    if not meshes:
        return
    mesh = meshes[0]
    count = len(mesh.data.vertices)
    check(count == vertices_expected, f"{label}: {vertices_expected} vertices (got {count})")
    values = colour_values(mesh)
    check(values is not None, f"{label}: per-vertex colours")
    if values:
        check(all(0.0 <= v <= 1.0 for v in values), f"{label}: colours within [0, 1]")
        check(max(values) - min(values) > 0.05, f"{label}: the colours vary (a pattern, not a constant)")
    if values and truth:
        # Order-free comparison (importers may reorder vertices): the sorted values of each
        # channel. Blender returns linear colours but keeps imported ones as 8-bit sRGB
        # (BYTE_COLOR), whose step is at most 0.0051 in linear terms, whatever the file held.
        worst = 0.0
        for c in range(3):
            seen = sorted(values[c::3])
            wanted = sorted(row[c] for row in truth)
            worst = max(worst, max(abs(a - b) for a, b in zip(seen, wanted)))
        check(worst < 0.006, f"{label}: colours equal photomat's vertex values (worst {worst:.4f})")


def check_volume(path, grids_expected):
    fresh_scene()
    directory, name = os.path.split(path)
    bpy.ops.object.volume_import(filepath=path, directory=directory, files=[{"name": name}])
    volumes = [o for o in bpy.context.scene.objects if o.type == "VOLUME"]
    check(len(volumes) == 1, f"{name}: one volume object (got {len(volumes)})")
    if not volumes:
        return
    grids = volumes[0].data.grids
    check(grids.load(), f"{name}: Blender's OpenVDB reads the grids ({grids.error_message})")
    names = sorted(g.name for g in grids)
    check(names == sorted(grids_expected), f"{name}: grids {sorted(grids_expected)} (got {names})")


def main():
    with open(os.path.join(out, "expected.json")) as f:
        expected = json.load(f)
    parts = expected["parts"]  # what this photomat builds (run-blender-import-test --parts)
    check_tile(os.path.join(out, "export", "tile.gltf"), expected["width"], expected["height"])
    if "carve" in parts:
        with open(os.path.join(out, "carve", "carve.json")) as f:
            carved_vertices = json.load(f)["vertices"]
        truth = read_vertex_values(os.path.join(out, "carve", "vertex_values.csv"))
        check_coloured_mesh("carved.glb", carved_vertices, lambda: bpy.ops.import_scene.gltf(
            filepath=os.path.join(out, "carve", "carved.glb")), truth)
        check_coloured_mesh("carved.ply", carved_vertices, lambda: bpy.ops.import_mesh.ply(
            filepath=os.path.join(out, "carve", "carved.ply")), truth)
    if "rd" in parts:
        with open(os.path.join(out, "rd", "summary.json")) as f:
            rd_vertices = json.load(f)["vertices"]
        check_coloured_mesh("rd pattern.glb", rd_vertices, lambda: bpy.ops.import_scene.gltf(
            filepath=os.path.join(out, "rd", "pattern.glb")))
    if "pbr" in parts:
        check_pbr_tile(os.path.join(out, "ggx-export"))
    if "solid" in parts:
        check_volume(os.path.join(out, "marble.vdb"), expected["vdb_grids"])
    if failures:
        raise SystemExit(f"{len(failures)} Blender import check(s) failed: {failures}")
    print("all Blender import checks passed")


main()
