"""Writes a gallery .blend for tools/texture_gallery.py from a material pack made by someone else: the texture
gallery's probe scene with every node group of the pack appended, one material per group (a group whose output is
a shader drives the Material Output; a group with Color / Normal outputs drives a Principled BSDF), named in the
scene's 'gallery' property. The pack is not part of the repository; the measurement in docs/shader-programs.md
used BlenderDefender/ProceduralNodes (functions/data/Procedural Nodes Basics.blend).

Run:  blender -b blend_scenes/texture_gallery.blend --python blend_scenes/make_external_gallery.py -- \\
          PACK.blend OUT.blend
then: /usr/bin/python3 tools/texture_gallery.py --blend OUT.blend --markdown OUT.md --png OUT.png
"""

import sys

import bpy


def main(pack, out):
    with bpy.data.libraries.load(pack, link=False) as (data_from, data_to):
        data_to.node_groups = list(data_from.node_groups)
    names = []
    for group in data_to.node_groups:
        outputs = [o for o in group.nodes if o.bl_idname == "NodeGroupOutput"]
        if not outputs:
            continue
        material = bpy.data.materials.new("pack_" + group.name.lower().replace(" ", "_"))
        material.use_nodes = True
        tree = material.node_tree
        node = tree.nodes.new("ShaderNodeGroup")
        node.node_tree = group
        shader = next((o for o in node.outputs if o.type == 'SHADER'), None)
        if shader is not None:
            tree.links.new(shader, tree.nodes["Material Output"].inputs["Surface"])
        elif "Color" in node.outputs:
            principled = tree.nodes["Principled BSDF"]
            tree.links.new(node.outputs["Color"], principled.inputs["Base Color"])
            if "Normal" in node.outputs:
                tree.links.new(node.outputs["Normal"], principled.inputs["Normal"])
        else:
            continue
        material.use_fake_user = True
        names.append(material.name)
    bpy.context.scene["gallery"] = names
    bpy.ops.wm.save_as_mainfile(filepath=out)
    print(f"make_external_gallery: {len(names)} materials: {names}")


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:]
    main(args[0], args[1])
