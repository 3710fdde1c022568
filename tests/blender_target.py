# Renders what tests/engine_target_test.cc checks, in Blender (headless, Cycles) with an equirect of
# `atmo render --target blender` as the world's Environment Texture:
#   1. a 10-degree perspective camera aimed at the direction where the sun should be (Blender's
#      world: x east, y north, z up): FILE_sun.exr, the sun at its centre if the map is right;
#   2. a white Lambertian plane facing up, seen from above by an orthographic camera, lit by the
#      world alone (no bounces): FILE_plane.exr, each pixel E / pi with E the plane's illuminance.
#   blender -b --factory-startup -P blender_target.py -- SKY.exr OUT AZIMUTH ELEVATION SAMPLES
import math
import sys

import bpy
from mathutils import Vector

argv = sys.argv[sys.argv.index('--') + 1:]
sky, out, azimuth, elevation, samples = argv[0], argv[1], float(argv[2]), float(argv[3]), int(argv[4])

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.engine = 'CYCLES'
scene.cycles.device = 'CPU'
scene.cycles.use_denoising = False
scene.render.image_settings.file_format = 'OPEN_EXR'
scene.render.image_settings.color_depth = '32'
scene.render.resolution_percentage = 100
scene.view_settings.view_transform = 'Standard'

# The world: Environment Texture -> Background, nearest texel (atmo's texels are already the
# pixel-integrated radiance, the sun disc's included).
world = bpy.data.worlds.new('atmo sky')
scene.world = world
world.use_nodes = True
nodes = world.node_tree.nodes
nodes.clear()
environment = nodes.new('ShaderNodeTexEnvironment')
environment.image = bpy.data.images.load(sky)
environment.interpolation = 'Closest'
background = nodes.new('ShaderNodeBackground')
output = nodes.new('ShaderNodeOutputWorld')
world.node_tree.links.new(environment.outputs['Color'], background.inputs['Color'])
world.node_tree.links.new(background.outputs['Background'], output.inputs['Surface'])

camera_data = bpy.data.cameras.new('camera')
camera = bpy.data.objects.new('camera', camera_data)
scene.collection.objects.link(camera)
scene.camera = camera

# 1. The sun.
camera_data.angle = math.radians(10.0)
a, e = math.radians(azimuth), math.radians(elevation)
towards_sun = Vector((math.sin(a) * math.cos(e), math.cos(a) * math.cos(e), math.sin(e)))
camera.rotation_mode = 'QUATERNION'
camera.rotation_quaternion = towards_sun.to_track_quat('-Z', 'Y')
scene.render.resolution_x = 65
scene.render.resolution_y = 65
scene.cycles.samples = 16
scene.render.filepath = out + '_sun.exr'
bpy.ops.render.render(write_still=True)

# 2. The plane.
bpy.ops.mesh.primitive_plane_add(size=2.0, location=(0.0, 0.0, 0.0))
plane = bpy.context.active_object
material = bpy.data.materials.new('white')
material.use_nodes = True
material_nodes = material.node_tree.nodes
material_nodes.clear()
diffuse = material_nodes.new('ShaderNodeBsdfDiffuse')
diffuse.inputs['Color'].default_value = (1.0, 1.0, 1.0, 1.0)
material_output = material_nodes.new('ShaderNodeOutputMaterial')
material.node_tree.links.new(diffuse.outputs['BSDF'], material_output.inputs['Surface'])
plane.data.materials.append(material)
camera_data.type = 'ORTHO'
camera_data.ortho_scale = 1.0
camera.rotation_mode = 'XYZ'
camera.rotation_euler = (0.0, 0.0, 0.0)  # looking down -z
camera.location = (0.0, 0.0, 5.0)
scene.render.resolution_x = 8
scene.render.resolution_y = 8
scene.cycles.samples = samples
scene.cycles.max_bounces = 0
scene.render.filepath = out + '_plane.exr'
bpy.ops.render.render(write_still=True)
