# Builds the glTF test scene in Blender and exports it with Blender's own glTF exporter, so that
# Omega's importer is tested on what a real DCC writes (issue 14). Optionally renders the same
# scene with Cycles, the reference the importer's output is compared with.
#
#   blender -b --factory-startup --python tests/data/gltf/make_scene.py -- OUT_DIR [--reference EXR [--spp N] [--only NAME]]
#
# --only NAME renders the reference with one light alone (PointLight, SpotLight, SunLight or
# EmissivePanel), to check each light's units on its own; the export is always the whole scene.
#
# Writes OUT_DIR/blender_scene.gltf (+ .bin + textures) and OUT_DIR/blender_scene.glb.
# Tested with Debian 12's Blender 3.4.1 (io_scene_gltf2 3.4): other versions may number things
# differently, and the tests check the numbers this version writes.
import math
import struct
import sys
import zlib

import bpy

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else ["."]
out_dir = argv[0]
cycles_exr = argv[argv.index("--reference") + 1] if "--reference" in argv else None


def write_png(path, w, h, pixel):
    # A tiny RGB PNG written by hand, so that the texture is procedural and byte-for-byte
    # reproducible (no dependence on Blender's image writer).
    raw = b"".join(b"\x00" + b"".join(bytes(pixel(x, y)) for x in range(w)) for y in range(h))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


# Base colour: an 8 x 8 checker of orange and blue; roughness (G channel, glTF's convention):
# stripes of 0.2 and 0.8.
checker = f"{out_dir}/checker.png"
write_png(checker, 32, 32, lambda x, y: (230, 120, 30) if (x // 4 + y // 4) % 2 == 0 else (30, 80, 200))
rough = f"{out_dir}/roughness.png"
write_png(rough, 16, 16, lambda x, y: (0, 51 if (x // 4) % 2 == 0 else 204, 0))

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene


def principled(name, base=(0.8, 0.8, 0.8), metallic=0.0, roughness=0.5, emission=None, strength=1.0):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    p = mat.node_tree.nodes["Principled BSDF"]
    p.inputs["Base Color"].default_value = (*base, 1)
    p.inputs["Metallic"].default_value = metallic
    p.inputs["Roughness"].default_value = roughness
    p.inputs["Specular"].default_value = 0.5  # F0 = 0.04: glTF's dielectric (ior 1.5)
    if emission:
        p.inputs["Emission"].default_value = (*emission, 1)
        p.inputs["Emission Strength"].default_value = strength
    return mat


def add(obj, mat):
    obj.data.materials.append(mat)
    return obj


# Floor: 8 x 8 m, grey and rough.
bpy.ops.mesh.primitive_plane_add(size=8, location=(0, 0, 0))
add(bpy.context.object, principled("Floor", base=(0.5, 0.5, 0.5), roughness=0.9)).name = "Floor"

# A textured cube (base colour and roughness maps), rotated and scaled by its node.
bpy.ops.mesh.primitive_cube_add(size=1, location=(-0.9, 0.3, 0.5), rotation=(0, 0, math.radians(30)))
cube = bpy.context.object
cube.name = "TexturedCube"
cube.scale = (1.0, 1.0, 1.0)
mat = principled("Checker", roughness=0.5)
nt = mat.node_tree
p = nt.nodes["Principled BSDF"]
img = nt.nodes.new("ShaderNodeTexImage")
img.image = bpy.data.images.load(checker)
nt.links.new(img.outputs["Color"], p.inputs["Base Color"])
rimg = nt.nodes.new("ShaderNodeTexImage")
rimg.image = bpy.data.images.load(rough)
rimg.image.colorspace_settings.name = "Non-Color"
sep = nt.nodes.new("ShaderNodeSeparateColor")
nt.links.new(rimg.outputs["Color"], sep.inputs["Color"])
nt.links.new(sep.outputs["Green"], p.inputs["Roughness"])
add(cube, mat)

# A gold metal sphere.
bpy.ops.mesh.primitive_uv_sphere_add(radius=0.6, location=(0.9, -0.2, 0.6), segments=24, ring_count=12)
bpy.ops.object.shade_smooth()
bpy.context.object.name = "GoldSphere"
add(bpy.context.object, principled("Gold", base=(1.0, 0.71, 0.29), metallic=1.0, roughness=0.3))

# An emissive panel facing the objects (its normal, +z locally, tilted towards them).
bpy.ops.mesh.primitive_plane_add(size=1, location=(0, 2.5, 1.8), rotation=(math.radians(120), 0, 0))
bpy.context.object.name = "EmissivePanel"
add(bpy.context.object, principled("Panel", base=(0, 0, 0), roughness=1.0, emission=(1.0, 0.8, 0.6), strength=4.0))

# Lights: Blender's watts; the exporter turns them into candela and lux (its 'SPEC' mode).
def light(kind, name, energy, loc, rot, color=(1, 1, 1), **kw):
    data = bpy.data.lights.new(name, kind)
    data.energy = energy
    data.color = color
    for k, v in kw.items():
        setattr(data, k, v)
    obj = bpy.data.objects.new(name, data)
    obj.location = loc
    obj.rotation_euler = [math.radians(a) for a in rot]
    scene.collection.objects.link(obj)
    return obj

light("POINT", "PointLight", 150.0, (2.0, -1.5, 2.5), (0, 0, 0), color=(1.0, 0.9, 0.8), shadow_soft_size=0)
light("SPOT", "SpotLight", 400.0, (-2.0, -2.0, 3.0), (40, 0, -45), color=(0.8, 0.9, 1.0),
      spot_size=math.radians(50), spot_blend=0.3, shadow_soft_size=0)
light("SUN", "SunLight", 1.5, (0, 0, 5), (30, 20, 0), angle=0)

# Cameras: a perspective one (first, the default) and an orthographic one looking down.
cam = bpy.data.cameras.new("MainCamera")
cam.lens_unit = "FOV"
cam.sensor_fit = "HORIZONTAL"
cam.angle = math.radians(50)
co = bpy.data.objects.new("MainCamera", cam)
co.location = (0.5, -6.0, 3.0)
co.rotation_euler = (math.radians(68), 0, math.radians(4))
scene.collection.objects.link(co)
top = bpy.data.cameras.new("TopCamera")
top.type = "ORTHO"
top.ortho_scale = 6.0
to = bpy.data.objects.new("TopCamera", top)
to.location = (0, 0, 8)
scene.collection.objects.link(to)
scene.camera = co

scene.render.resolution_x = 160
scene.render.resolution_y = 120
scene.world = bpy.data.worlds.new("World")
scene.world.color = (0, 0, 0)

for fmt, ext in (("GLTF_SEPARATE", "gltf"), ("GLB", "glb")):
    bpy.ops.export_scene.gltf(filepath=f"{out_dir}/blender_scene.{ext}", export_format=fmt,
                              export_cameras=True, export_lights=True, export_apply=True)

if cycles_exr and "--only" in argv:
    only = argv[argv.index("--only") + 1]
    for obj in list(scene.collection.objects):
        if obj.type == "LIGHT" and obj.name != only:
            bpy.data.objects.remove(obj)
    if only != "EmissivePanel":
        bpy.data.materials["Panel"].node_tree.nodes["Principled BSDF"].inputs["Emission Strength"].default_value = 0

if cycles_exr:
    # The reference: Cycles, Standard view transform (no Filmic), linear EXR, no denoising.
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = int(argv[argv.index("--spp") + 1]) if "--spp" in argv else 256
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 16
    scene.cycles.sample_clamp_direct = 0
    scene.cycles.sample_clamp_indirect = 0
    scene.cycles.filter_width = 0.01  # box-like, as Omega's default film filter
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = cycles_exr
    bpy.ops.render.render(write_still=True)
