#!/usr/bin/env python3
"""Render a glTF scene with Mitsuba 3, following vcm-rs's scene conventions.

An independent reference for the renderer: the same file, read by this script
into Mitsuba 3's own plugins, should give the same image as `vcm render` up to
noise. It covers the part of the conventions that Mitsuba models exactly:

- Lambertian diffuse (`metallicFactor` 0, `roughnessFactor` 1, specular 0), its
  base colour from a factor or from a texture (sRGB, the sampler's wrap and filter),
- mirrors and rough conductors whose base colour is white (F0 = 1, so Schlick
  and Mitsuba's conductor agree), and rough conductors of any base colour as
  Mitsuba's fully metallic `principled` (Schlick from the base colour; coloured
  perfect mirrors are refused),
- smooth and rough dielectric solids (transmission 1 with `KHR_materials_volume`)
  and smooth thin-walled sheets (without it), the base colour tinting transmission;
  a solid's `attenuationColor` / `attenuationDistance` as a purely absorbing
  homogeneous interior medium (then Mitsuba's volumetric path tracer renders),
- one-sided area lights (`emissiveFactor` x `emissiveStrength`, or an sRGB
  emissive texture where their product is 1 and the UVs map the unit square
  once, as Mitsuba samples a textured emitter through its UV map),
- `KHR_lights_punctual` point and directional lights, and spot lights whose cones
  are less than 0.01 rad apart (Mitsuba draws the edge between them differently),
- the `VCM_environment` extension: a constant colour, or an equirectangular image
  (OpenEXR or Radiance HDR, from a file),
- `alphaMode` MASK cut-outs (the base colour alpha against `alphaCutoff`) where the
  texture is sampled nearest (then Mitsuba's volumetric path tracer renders, whose shadow
  rays pass through the cut-outs),
- the first perspective camera (or none: framed from +Z as the conventions say).

Anything else (other textures, texture transforms, the glTF dielectric-base
layer, spot lights with a soft edge, alpha blending) stops the script with a message, so that a reference is never silently a different scene.

Usage:
    python3 -m pip install -r tools/requirements.txt
    python3 tools/mitsuba_reference.py scenes/cornell-box.gltf ref.exr \
        --width 256 --height 256 --spp 1024 [--seed 0] [--max-depth -1] [--rr-depth 5] \
        [--variant scalar_rgb]

With several seeds (`--seed 1 2 3`) the scene is loaded once and rendered once per seed,
each image written to the output path with `{seed}` replaced by its seed
(`ref-{seed}.exr`).

`--variant llvm_ad_rgb` renders with Mitsuba's vectorized LLVM back end instead of the
scalar one (the cross-check's): it needs a libLLVM that Dr.Jit can compile with, e.g.
Debian's `apt-get install libllvm19` and `DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so`
(libLLVM 15 stops with "Cannot select ... fminimum").
"""

import argparse
import base64
import json
import math
import os
import struct
import sys
import tempfile
import time
import urllib.parse

import drjit as dr
import mitsuba as mi
import numpy as np


class Unsupported(Exception):
    """A feature of the file that this script cannot give Mitsuba exactly."""


COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
              5125: np.uint32, 5126: np.float32}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def load_buffers(doc, base_dir):
    buffers = []
    for buffer in doc["buffers"]:
        uri = buffer["uri"]
        if uri.startswith("data:"):
            buffers.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            with open(os.path.join(base_dir, uri), "rb") as f:
                buffers.append(f.read())
    return buffers


def read_accessor(doc, buffers, index):
    accessor = doc["accessors"][index]
    view = doc["bufferViews"][accessor["bufferView"]]
    dtype = np.dtype(COMPONENTS[accessor["componentType"]])
    width = WIDTH[accessor["type"]]
    count = accessor["count"]
    start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
    stride = view.get("byteStride", dtype.itemsize * width)
    data = buffers[view["buffer"]]
    array = np.ndarray((count, width), dtype, buffer=data, offset=start,
                       strides=(stride, dtype.itemsize)).copy()
    return array if width > 1 else array.reshape(count)


def quaternion_matrix(q):
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def local_matrix(node):
    if "matrix" in node:
        return np.array(node["matrix"], dtype=float).reshape(4, 4).T
    m = np.eye(4)
    m[:3, :3] = quaternion_matrix(node.get("rotation", [0, 0, 0, 1])) @ np.diag(
        node.get("scale", [1, 1, 1]))
    m[:3, 3] = node.get("translation", [0, 0, 0])
    return m


def world_nodes(doc):
    """Yields (node, world matrix) for every node of the default scene."""
    scene = doc["scenes"][doc.get("scene", 0)]
    stack = [(i, np.eye(4)) for i in scene["nodes"]]
    while stack:
        index, parent = stack.pop()
        node = doc["nodes"][index]
        world = parent @ local_matrix(node)
        yield node, world
        stack.extend((child, world) for child in node.get("children", []))


def rgb(value):
    return {"type": "rgb", "value": [float(v) for v in value]}


WRAP = {10497: "repeat", 33648: "mirror", 33071: "clamp"}
NEAREST = (9728, 9984, 9986)  # NEAREST and the NEAREST_MIPMAP_* minification filters


def colour_texture(doc, base_dir, work_dir, info, name):
    """A Mitsuba bitmap for a glTF base colour or emissive texture (sRGB-decoded, as glTF
    says for both)."""
    if info.get("texCoord", 0) != 0 or "extensions" in info:
        raise Unsupported(f"material {name!r}: a texture on another UV set or transformed")
    texture = doc["textures"][info["index"]]
    image = doc["images"][texture["source"]]
    sampler = doc.get("samplers", [{}])[texture["sampler"]] if "sampler" in texture else {}
    wrap = {WRAP[sampler.get("wrapS", 10497)], WRAP[sampler.get("wrapT", 10497)]}
    if len(wrap) != 1:
        raise Unsupported(f"material {name!r}: different wrap modes in u and v")
    # One filter per lookup, as the renderer chooses it: magnification decides, else
    # minification, else bilinear.
    decides = sampler.get("magFilter", sampler.get("minFilter"))
    uri = image.get("uri")
    if uri is None:
        raise Unsupported(f"material {name!r}: an image in a buffer view")
    if uri.startswith("data:"):
        header, payload = uri.split(",", 1)
        path = os.path.join(work_dir, f"image{info['index']}.{header.split('/')[1].split(';')[0]}")
        with open(path, "wb") as f:
            f.write(base64.b64decode(payload))
    else:
        path = os.path.join(base_dir, urllib.parse.unquote(uri))
    return {"type": "bitmap", "filename": path, "raw": False,
            "filter_type": "nearest" if decides in NEAREST else "bilinear",
            "wrap_mode": wrap.pop()}


def alpha_mask(bsdf, material, doc, base_dir, work_dir):
    """`bsdf` cut out where the material's alpha (base colour alpha factor times the base
    colour texture's alpha, linear) is below `alphaCutoff`, as a Mitsuba `mask` whose opacity
    is 0 or 1 per texel; the texture must be sampled nearest, as Mitsuba would otherwise blend
    opacities across texel edges where glTF cuts the filtered alpha."""
    name = material.get("name")
    pbr = material.get("pbrMetallicRoughness", {})
    cutoff = material.get("alphaCutoff", 0.5)
    factor = pbr.get("baseColorFactor", [1, 1, 1, 1])[3]
    info = pbr.get("baseColorTexture")
    if info is None:
        return bsdf if factor >= cutoff else {"type": "mask", "opacity": 0.0, "material": bsdf}
    texture = colour_texture(doc, base_dir, work_dir, info, name)
    if texture["filter_type"] != "nearest":
        raise Unsupported(f"material {name!r}: an alpha mask sampled with a linear filter")
    texels = np.array(mi.Bitmap(texture["filename"]))
    if texels.ndim == 3 and texels.shape[2] == 4:
        scale = np.iinfo(texels.dtype).max if texels.dtype.kind == "u" else 1.0
        alpha = texels[:, :, 3].astype(np.float64) / scale
    else:
        alpha = np.ones(texels.shape[:2])
    opacity = (alpha * factor >= cutoff).astype(np.float32)[:, :, None]
    return {"type": "mask", "material": bsdf,
            "opacity": {"type": "bitmap", "bitmap": mi.Bitmap(opacity), "raw": True,
                        "filter_type": "nearest", "wrap_mode": texture["wrap_mode"]}}


def interior_medium(material):
    """The absorbing medium inside a solid dielectric with `KHR_materials_volume`
    attenuation (Beer-Lambert: sigma = -ln(attenuationColor) / attenuationDistance), or
    None for a clear solid or any other material."""
    ext = material.get("extensions", {})
    volume = ext.get("KHR_materials_volume", {})
    transmission = ext.get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0)
    distance = volume.get("attenuationDistance", math.inf)
    if transmission <= 0.0 or volume.get("thicknessFactor", 0.0) <= 0.0 or math.isinf(distance):
        return None
    colour = [min(max(c, 1e-38), 1.0) for c in volume.get("attenuationColor", [1, 1, 1])]
    sigma = [-math.log(c) / distance for c in colour]
    # Mitsuba reads an RGB `sigma_t` as a reflectance (at most 1): scale it into that range.
    scale = max(max(sigma), 1e-30)
    return {"type": "homogeneous", "albedo": 0.0,
            "sigma_t": rgb([v / scale for v in sigma]), "scale": scale}


def material_plugins(material, doc, base_dir, work_dir):
    """The Mitsuba BSDF and, for an emitter, the area light of a glTF material."""
    ext = material.get("extensions", {})
    for name in ext:
        if name not in ("KHR_materials_specular", "KHR_materials_transmission",
                        "KHR_materials_ior", "KHR_materials_volume",
                        "KHR_materials_emissive_strength"):
            raise Unsupported(f"material {material.get('name')!r} uses {name}")
    pbr = material.get("pbrMetallicRoughness", {})
    if "metallicRoughnessTexture" in pbr:
        raise Unsupported(f"material {material.get('name')!r} has a metallicRoughnessTexture")
    # Mitsuba's `normalmap` is another shading-normal model: a diffuse plane whose normal map
    # tilts it by 40 degrees reflects 0.79 of a uniform sky's light there, where the cosine
    # about the shading normal, clipped to the geometric hemisphere, gives (1 + cos 40°) / 2
    # = 0.88 (the renderer's value, tested in crates/vcm/tests/integration/environment.rs).
    # Vertex normals differ too (Mitsuba lets in light from below the geometric plane: 1.0
    # there), so scenes whose vertex normals lean far off their faces make poor cross-checks.
    if "normalTexture" in material:
        raise Unsupported(f"material {material.get('name')!r} has a normalTexture")
    base = pbr.get("baseColorFactor", [1, 1, 1, 1])[:3]
    metallic = pbr.get("metallicFactor", 1.0)
    roughness = pbr.get("roughnessFactor", 1.0)
    transmission = ext.get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0)
    ior = ext.get("KHR_materials_ior", {}).get("ior", 1.5)
    specular = ext.get("KHR_materials_specular", {}).get("specularFactor", 1.0)
    thickness = ext.get("KHR_materials_volume", {}).get("thicknessFactor", 0.0)
    two_sided = material.get("doubleSided", False)

    if "baseColorTexture" in pbr and not (metallic == 0.0 and transmission == 0.0):
        raise Unsupported(f"material {material.get('name')!r}: a texture on a non-diffuse material")
    if metallic == 1.0 and roughness > 0.0 and any(c != 1.0 for c in base):
        # Mitsuba's `conductor` takes a complex index of refraction; its `principled`, fully
        # metallic, is GGX with alpha = roughness^2 and Schlick's Fresnel from the base colour.
        bsdf = {"type": "principled", "base_color": rgb(base), "metallic": 1.0,
                "roughness": roughness}
    elif metallic == 1.0:
        if any(c != 1.0 for c in base):
            raise Unsupported(f"mirror {material.get('name')!r} with base colour "
                              f"{base}: Schlick F0 other than 1")
        if roughness == 0.0:
            bsdf = {"type": "conductor", "material": "none"}
        else:
            bsdf = {"type": "roughconductor", "material": "none",
                    "distribution": "ggx", "alpha": roughness ** 2}
    elif metallic == 0.0 and transmission == 1.0:
        if thickness <= 0.0 and roughness > 0.0:
            raise Unsupported(f"rough thin-walled dielectric {material.get('name')!r}")
        if thickness <= 0.0:
            bsdf = {"type": "thindielectric", "int_ior": ior, "ext_ior": 1.0}
        elif roughness == 0.0:
            bsdf = {"type": "dielectric", "int_ior": ior, "ext_ior": 1.0}
        else:
            bsdf = {"type": "roughdielectric", "int_ior": ior, "ext_ior": 1.0,
                    "distribution": "ggx", "alpha": roughness ** 2}
        bsdf["specular_transmittance"] = rgb(base)  # glTF: the base colour tints transmission
        two_sided = False
    elif metallic == 0.0 and transmission == 0.0 and specular == 0.0 and roughness == 1.0:
        bsdf = {"type": "diffuse", "reflectance": rgb(base)}
        if "baseColorTexture" in pbr:
            if any(c != 1.0 for c in base):
                raise Unsupported(f"material {material.get('name')!r}: a base colour texture "
                                  "times a factor other than 1")
            bsdf["reflectance"] = colour_texture(doc, base_dir, work_dir,
                                                 pbr["baseColorTexture"], material.get("name"))
    else:
        raise Unsupported(f"material {material.get('name')!r} (metallic {metallic}, "
                          f"roughness {roughness}, specular {specular}, "
                          f"transmission {transmission}) has the glTF dielectric layer")
    if two_sided:
        bsdf = {"type": "twosided", "material": bsdf}
    alpha_mode = material.get("alphaMode", "OPAQUE")
    if alpha_mode == "BLEND":
        raise Unsupported(f"material {material.get('name')!r} is alpha-blended")
    if alpha_mode == "MASK":
        if np.any(np.array(material.get("emissiveFactor", [0, 0, 0])) > 0):
            raise Unsupported(f"material {material.get('name')!r}: an alpha-masked emitter")
        bsdf = alpha_mask(bsdf, material, doc, base_dir, work_dir)

    emissive = np.array(material.get("emissiveFactor", [0, 0, 0]), dtype=float)
    strength = ext.get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
    emitter = None
    if "emissiveTexture" in material:
        if np.any(emissive * strength != 1.0):
            raise Unsupported(f"material {material.get('name')!r}: an emissive texture times "
                              "a factor other than 1")
        emitter = {"type": "area", "radiance": colour_texture(
            doc, base_dir, work_dir, material["emissiveTexture"], material.get("name"))}
    elif np.any(emissive > 0):
        emitter = {"type": "area", "radiance": rgb(emissive * strength)}
    return bsdf, emitter


# How many times finer than the image the grid handed to Mitsuba's envmap is, per axis.
ENVMAP_UPSAMPLE = 8


def environment_plugin(environment, base_dir, work_dir):
    """Mitsuba's emitter for the `VCM_environment` extension: a constant, or an envmap.

    vcm-rs's map is constant over each pixel, its rows spanning equal polar angles from the
    zenith. Mitsuba's envmap interpolates bilinearly between grid points whose first row
    lies on the zenith and whose last lies on the nadir. So the image is sampled at the
    points of a grid ENVMAP_UPSAMPLE times finer: the two then differ only next to the
    pixels' edges. The two maps' centre columns look along +X (vcm-rs) and +Z (Mitsuba):
    the envmap is turned 90 degrees about +Y.
    """
    colour = np.array(environment.get("color", [1, 1, 1]), dtype=float)
    colour = colour * environment.get("strength", 1.0)
    if "image" not in environment:
        return {"type": "constant", "radiance": rgb(colour)}
    uri = environment["image"]
    if uri.startswith("data:"):
        raise Unsupported("an environment image in a data URI")
    bitmap = mi.Bitmap(os.path.join(base_dir, urllib.parse.unquote(uri)))
    texels = np.array(bitmap.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32,
                                     srgb_gamma=False))
    height, width = texels.shape[:2]
    rows, cols = height * ENVMAP_UPSAMPLE, width * ENVMAP_UPSAMPLE
    # Polar angle / pi of each grid row, azimuthal coordinate of each grid column.
    v = np.arange(rows) / (rows - 1)
    u = (np.arange(cols) + 0.5) / cols
    source_rows = np.minimum((v * height).astype(int), height - 1)
    source_cols = np.minimum((u * width).astype(int), width - 1)
    grid = texels[source_rows][:, source_cols] * colour
    path = os.path.join(work_dir, "environment.exr")
    mi.Bitmap(grid.astype(np.float32)).write(path)
    return {"type": "envmap", "filename": path,
            "to_world": mi.ScalarTransform4f().rotate(axis=[0, 1, 0], angle=90)}


def write_ply(path, positions, normals, uvs, faces):
    """A binary little-endian PLY with float positions (normals, UVs) and int faces."""
    with open(path, "wb") as f:
        header = ["ply", "format binary_little_endian 1.0",
                  f"element vertex {len(positions)}",
                  "property float x", "property float y", "property float z"]
        if normals is not None:
            header += ["property float nx", "property float ny", "property float nz"]
        if uvs is not None:
            header += ["property float u", "property float v"]
        header += [f"element face {len(faces)}",
                   "property list uchar int vertex_indices", "end_header"]
        f.write(("\n".join(header) + "\n").encode())
        columns = [a for a in (positions, normals, uvs) if a is not None]
        f.write(np.hstack(columns).astype("<f4").tobytes())
        for a, b, c in faces:
            f.write(struct.pack("<Biii", 3, int(a), int(b), int(c)))


def transform_points(m, p):
    return (np.hstack([p, np.ones((len(p), 1))]) @ m.T)[:, :3]


def transform_normals(m, n):
    out = n @ np.linalg.inv(m[:3, :3])
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def scene_dict(path, width, height, max_depth, rr_depth, spp, seed, work_dir):
    base_dir = os.path.dirname(os.path.abspath(path))
    with open(path) as f:
        doc = json.load(f)
    buffers = load_buffers(doc, base_dir)
    scene = {"type": "scene",
             "integrator": {"type": "path", "max_depth": max_depth, "rr_depth": rr_depth}}
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    camera = None
    lights = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    for node, world in world_nodes(doc):
        if "camera" in node and camera is None:
            camera = (doc["cameras"][node["camera"]], world)
        light = node.get("extensions", {}).get("KHR_lights_punctual")
        if light is not None:
            spec = lights[light["light"]]
            value = np.array(spec.get("color", [1, 1, 1])) * spec.get("intensity", 1.0)
            if spec["type"] == "point":
                scene[f"light{len(scene)}"] = {
                    "type": "point", "position": world[:3, 3].tolist(),
                    "intensity": rgb(value)}
            elif spec["type"] == "directional":
                direction = -world[:3, 2] / np.linalg.norm(world[:3, 2])
                scene[f"light{len(scene)}"] = {
                    "type": "directional", "direction": direction.tolist(),
                    "irradiance": rgb(value)}
            elif spec["type"] == "spot":
                # Mitsuba's falloff between the cones is linear in angle, glTF's is quadratic
                # in cosine: only cones closer than 0.01 rad leave too little between them.
                cone = spec.get("spot", {})
                inner, outer = cone.get("innerConeAngle", 0.0), cone.get("outerConeAngle", math.pi / 4)
                if outer - inner > 0.01:
                    raise Unsupported("a spot light with a soft edge (cones more than 0.01 rad apart)")
                position = world[:3, 3]
                direction = -world[:3, 2] / np.linalg.norm(world[:3, 2])
                up = np.array([0.0, 1.0, 0.0]) if abs(direction[1]) < 0.9 else np.array([1.0, 0, 0])
                scene[f"light{len(scene)}"] = {
                    "type": "spot", "intensity": rgb(value),
                    "cutoff_angle": math.degrees(outer), "beam_width": math.degrees(inner),
                    "to_world": mi.ScalarTransform4f().look_at(
                        origin=position.tolist(), target=(position + direction).tolist(),
                        up=up.tolist())}
            else:
                raise Unsupported(f"a {spec['type']} light")
        if "mesh" not in node:
            continue
        for primitive in doc["meshes"][node["mesh"]]["primitives"]:
            if primitive.get("mode", 4) != 4:
                raise Unsupported("a primitive that is not a triangle list")
            attributes = primitive["attributes"]
            positions = transform_points(world, read_accessor(doc, buffers, attributes["POSITION"]))
            normals = None
            if "NORMAL" in attributes:
                normals = transform_normals(world, read_accessor(doc, buffers, attributes["NORMAL"]))
            uvs = None
            if "TEXCOORD_0" in attributes:
                uvs = read_accessor(doc, buffers, attributes["TEXCOORD_0"])
                if uvs.dtype != np.float32:
                    raise Unsupported("normalized integer texture coordinates")
            if "indices" in primitive:
                faces = read_accessor(doc, buffers, primitive["indices"]).reshape(-1, 3)
            else:
                faces = np.arange(len(positions)).reshape(-1, 3)
            if np.linalg.det(world[:3, :3]) < 0:
                faces = faces[:, ::-1]
            material = doc["materials"][primitive["material"]] if "material" in primitive else {}
            bsdf, emitter = material_plugins(material, doc, base_dir, work_dir)
            medium = interior_medium(material)
            if emitter is not None:
                normals = None  # emitters are flat: the winding order picks their front
            ply = os.path.join(work_dir, f"mesh{len(scene)}.ply")
            if emitter is not None and emitter["radiance"]["type"] == "bitmap":
                # Mitsuba samples a textured emitter through its UV map, so that map has to
                # cover the unit square once: at least it must stay within it.
                if uvs is None or uvs.min() < 0.0 or uvs.max() > 1.0:
                    raise Unsupported("an emissive texture with UVs outside [0, 1]")
            write_ply(ply, positions, normals, uvs, faces)
            shape = {"type": "ply", "filename": ply, "bsdf": bsdf}
            if normals is None:
                shape["face_normals"] = True
            if emitter is not None:
                shape["emitter"] = emitter
            if medium is not None:
                shape["interior"] = medium
            # Mitsuba's path tracer stops shadow rays at any surface; its volumetric one
            # lets them through cut-outs and index-matched boundaries.
            if medium is not None or bsdf["type"] == "mask":
                scene["integrator"]["type"] = "volpath"
            scene[f"shape{len(scene)}"] = shape
            lo, hi = np.minimum(lo, positions.min(0)), np.maximum(hi, positions.max(0))

    environment = doc.get("extensions", {}).get("VCM_environment")
    if environment is not None:
        scene["environment"] = environment_plugin(environment, base_dir, work_dir)

    if camera is not None:
        perspective = camera[0].get("perspective")
        if perspective is None:
            raise Unsupported("an orthographic camera")
        yfov = perspective["yfov"]
        world = camera[1]
        origin, forward, up = world[:3, 3], -world[:3, 2], world[:3, 1]
    else:
        yfov = math.radians(45.0)
        centre, extent = (lo + hi) / 2, (hi - lo) / 2
        radius = float(np.linalg.norm(extent))
        origin = centre + np.array([0, 0, radius / math.sin(yfov / 2)])
        forward, up = np.array([0, 0, -1.0]), np.array([0, 1.0, 0])
    # Mitsuba clips at 10^4 units by default: scale the clip range with the scene instead.
    far = 10.0 * (float(np.linalg.norm(hi - lo)) + float(np.linalg.norm(origin - (lo + hi) / 2)))
    scene["sensor"] = {
        "type": "perspective", "fov_axis": "y", "fov": math.degrees(yfov),
        "near_clip": 1e-6 * far, "far_clip": far,
        "to_world": mi.ScalarTransform4f().look_at(
            origin=origin.tolist(), target=(origin + forward).tolist(), up=up.tolist()),
        "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        "film": {"type": "hdrfilm", "width": width, "height": height,
                 "pixel_format": "rgb", "rfilter": {"type": "box"}},
    }
    return scene


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene")
    parser.add_argument("output")
    parser.add_argument("--width", type=int, default=256)
    parser.add_argument("--height", type=int, default=256)
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--seed", type=int, nargs="+", default=[0],
                        help="one render per seed; with several, OUTPUT names them with {seed}")
    parser.add_argument("--max-depth", type=int, default=-1,
                        help="segments, as `vcm render --max-depth`; -1: unlimited")
    parser.add_argument("--rr-depth", type=int, default=5,
                        help="depth where Russian roulette starts (Mitsuba's default 5; "
                        "vcm-rs starts after 3 segments)")
    parser.add_argument("--variant", choices=["scalar_rgb", "llvm_ad_rgb"],
                        default="scalar_rgb",
                        help="Mitsuba back end: scalar, or vectorized through LLVM")
    args = parser.parse_args()
    if len(args.seed) > 1 and "{seed}" not in args.output:
        parser.error("with several seeds, the output path must contain {seed}")

    mi.set_variant(args.variant)
    with tempfile.TemporaryDirectory() as work_dir:
        try:
            scene = scene_dict(args.scene, args.width, args.height, args.max_depth,
                               args.rr_depth, args.spp, args.seed[0], work_dir)
        except Unsupported as error:
            sys.exit(f"{args.scene}: not converted to Mitsuba: {error}")
        except (OSError, ValueError, KeyError, IndexError) as error:
            sys.exit(f"{args.scene}: cannot read it: {error!r}")
        scene = mi.load_dict(scene)
        for seed in args.seed:
            render(scene, args, seed)


def render(scene, args, seed):
    """Renders `scene` with `seed` and writes the image to the output path of that seed."""
    start = time.perf_counter()
    image = mi.render(scene, spp=args.spp, seed=seed)
    # The LLVM back end records the render and runs it when its result is needed.
    dr.eval(image)
    dr.sync_thread()
    seconds = time.perf_counter() - start
    samples = args.width * args.height * args.spp
    print(f"rendered {args.spp} spp at {args.width}x{args.height} in {seconds:.2f} s: "
          f"{samples / seconds / 1e6:.2f} M samples/s", file=sys.stderr)
    mi.util.write_bitmap(args.output.replace("{seed}", str(seed)), image)


if __name__ == "__main__":
    main()
