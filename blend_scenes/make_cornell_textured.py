"""Writes cornell_textured.blend next to this script: the caustic Cornell box (make_cornell.py) with every
diffuse surface driven by node graphs, the texture-heavy frame of the node-program benchmark
(docs/benchmarks.md): a brick floor with bump, walls whose colour is noise through a ColorRamp, a Voronoi
block with textured roughness, and the glass and mirror spheres of the caustic box.

Run:  blender -b --factory-startup --python blend_scenes/make_cornell_textured.py
"""

import sys
from pathlib import Path

import bpy

sys.path.insert(0, str(Path(__file__).resolve().parent))
import make_cornell as cornell  # noqa: E402
from scene_kit import glass_material, save  # noqa: E402


def _nodes(material):
    material.use_nodes = True
    tree = material.node_tree
    return tree.nodes, tree.links


def brick_floor(name):
    """Brick Texture colours the floor and, through a Bump of its Fac, dents the mortar."""
    material = bpy.data.materials.new(name)
    nodes, links = _nodes(material)
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = 0.6
    coords = nodes.new("ShaderNodeTexCoord")
    brick = nodes.new("ShaderNodeTexBrick")
    brick.inputs["Scale"].default_value = 4.0
    brick.inputs["Color1"].default_value = (0.55, 0.25, 0.18, 1.0)
    brick.inputs["Color2"].default_value = (0.40, 0.20, 0.15, 1.0)
    brick.inputs["Mortar"].default_value = (0.7, 0.7, 0.68, 1.0)
    bump = nodes.new("ShaderNodeBump")
    bump.inputs["Distance"].default_value = 0.02
    links.new(coords.outputs["Object"], brick.inputs["Vector"])
    links.new(brick.outputs["Color"], bsdf.inputs["Base Color"])
    links.new(brick.outputs["Fac"], bump.inputs["Height"])
    links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
    return material


def noisy_wall(name, dark, light):
    """Noise through a ColorRamp between two colours, on a Diffuse BSDF."""
    material = bpy.data.materials.new(name)
    nodes, links = _nodes(material)
    nodes.remove(nodes["Principled BSDF"])
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    links.new(diffuse.outputs["BSDF"], nodes["Material Output"].inputs["Surface"])
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 6.0
    noise.inputs["Detail"].default_value = 6.0
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (*dark, 1.0)
    ramp.color_ramp.elements[1].color = (*light, 1.0)
    links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], diffuse.inputs["Color"])
    return material


def voronoi_block(name):
    """Voronoi cells colour a Principled surface; a Noise through Map Range sets its roughness."""
    material = bpy.data.materials.new(name)
    nodes, links = _nodes(material)
    bsdf = nodes["Principled BSDF"]
    voronoi = nodes.new("ShaderNodeTexVoronoi")
    voronoi.inputs["Scale"].default_value = 8.0
    mix = nodes.new("ShaderNodeMixRGB")
    mix.inputs["Color1"].default_value = (0.8, 0.8, 0.75, 1.0)
    links.new(voronoi.outputs["Color"], mix.inputs["Color2"])
    mix.inputs["Fac"].default_value = 0.4
    links.new(mix.outputs["Color"], bsdf.inputs["Base Color"])
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 3.0
    map_range = nodes.new("ShaderNodeMapRange")
    map_range.inputs["To Min"].default_value = 0.2
    map_range.inputs["To Max"].default_value = 0.7
    links.new(noise.outputs["Fac"], map_range.inputs["Value"])
    links.new(map_range.outputs["Result"], bsdf.inputs["Roughness"])
    return material


def make_textured():
    scene = cornell.new_empty_scene()
    box = cornell.add_box(scene)
    materials = box.data.materials
    materials[0] = brick_floor("Brick")
    materials[1] = noisy_wall("RedNoise", (0.35, 0.03, 0.02), cornell.RED)
    materials[2] = noisy_wall("GreenNoise", (0.05, 0.2, 0.04), cornell.GREEN)
    cornell.add_block(scene, "VoronoiBlock", (0.5, 0.5, 0.9), (0.45, 0.3), 20.0, voronoi_block("Voronoi"))
    cornell.add_sphere(scene, "GlassSphere", cornell.GLASS_SPHERE_CENTER, glass_material("Glass"))
    cornell.add_sphere(scene, "MirrorSphere", (-0.45, 0.45, cornell.SPHERE_RADIUS), cornell.mirror_material("Mirror"))
    cornell.add_light(scene, cornell.CAUSTICS_LIGHT_LOCATION)
    cornell.add_camera(scene)
    save("cornell_textured.blend")


if __name__ == "__main__":
    make_textured()
