"""Writes the composed USD stage that tests/integration/animation_falls.rs
reads, and the oracle it is checked against: what Pixar's own library
(pip install usd-core; written with usd-core 26.11) makes of it.

    python make.py

- card_mesh.usda: a 4 x 1 cm card's Mesh, the payload of
- card_asset.usda, written here as the crate file card_asset.usdc: an
  Xform `card` (its default prim) with a variant set `size` whose "small"
  and "large" variants scale it by 1 and 2, holding the Mesh by payload;
- anim.usda: `over` opinions only, the card's translate and rotateXYZ keys
  of ../../blender/tumble_thick.usda (Blender's export of the MuJoCo
  tumble_thick fall, time codes 1..241 at 24 per second);
- shot.usda: anim.usda as a sublayer retimed by offset 10, scale 0.5 (so
  the keys fall on codes 10.5 .. 130.5 and the fall runs twice as fast),
  a prim `leaf` that references card_asset.usdc, selects the "large"
  variant and inherits its xformOpOrder from a class `_paper`, and an
  inactive prim `stone` with a mesh of its own;
- shot.flat.usda: the oracle, Usd.Stage.Open('shot.usda').Flatten();
- tumble_thick.usdz, tumble_thick_crate.usd, tumble_thick_rigged.usdc and
  skinned_leaf.usdc: the Blender layers and ../skinned_leaf.usda as crate
  files and a USDZ package (Sdf.Layer.Export, UsdUtils.CreateNewUsdzPackage).
"""
import os
from pxr import Sdf, Usd, UsdUtils

HERE = os.path.dirname(os.path.abspath(__file__))
BLENDER = os.path.join(HERE, "..", "..", "blender")


def write(name, text):
    with open(os.path.join(HERE, name), "w") as f:
        f.write(text)


write("card_mesh.usda", """#usda 1.0
(
    defaultPrim = "card"
    metersPerUnit = 1
    upAxis = "Z"
)

def Mesh "card"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-0.02, -0.005, 0), (0.02, -0.005, 0), (0.02, 0.005, 0), (-0.02, 0.005, 0)]
}
""")

write("card_asset.usda", """#usda 1.0
(
    defaultPrim = "card"
    metersPerUnit = 1
    upAxis = "Z"
)

def Xform "card" (
    prepend variantSets = "size"
    variants = {
        string size = "small"
    }
)
{
    def "card" (
        prepend payload = @./card_mesh.usda@
    )
    {
    }

    variantSet "size" = {
        "large" {
            float3 xformOp:scale = (2, 2, 2)
        }
        "small" {
            float3 xformOp:scale = (1, 1, 1)
        }
    }
}
""")
Sdf.Layer.FindOrOpen(os.path.join(HERE, "card_asset.usda")).Export(
    os.path.join(HERE, "card_asset.usdc"))
os.remove(os.path.join(HERE, "card_asset.usda"))

blender = Sdf.Layer.FindOrOpen(os.path.join(BLENDER, "tumble_thick.usda"))
anim = Sdf.Layer.CreateAnonymous(".usda")
leaf = Sdf.CreatePrimInLayer(anim, "/shot/leaf")
for name in ["xformOp:translate", "xformOp:rotateXYZ"]:
    src = blender.GetAttributeAtPath("/root/card." + name)
    dst = Sdf.AttributeSpec(leaf, name, src.typeName)
    for t in blender.ListTimeSamplesForPath(src.path):
        anim.SetTimeSample(dst.path, t, blender.QueryTimeSample(src.path, t))
anim.Export(os.path.join(HERE, "anim.usda"))

write("shot.usda", """#usda 1.0
(
    defaultPrim = "shot"
    metersPerUnit = 1
    subLayers = [
        @./anim.usda@ (offset = 10; scale = 0.5)
    ]
    timeCodesPerSecond = 24
    upAxis = "Z"
)

class "_paper"
{
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ", "xformOp:scale"]
}

def Xform "shot"
{
    def Xform "leaf" (
        prepend inherits = </_paper>
        prepend references = @./card_asset.usdc@
        variants = {
            string size = "large"
        }
    )
    {
    }

    def Xform "stone" (
        active = false
    )
    {
        def Mesh "stone"
        {
            int[] faceVertexCounts = [3]
            int[] faceVertexIndices = [0, 1, 2]
            point3f[] points.timeSamples = {
                0: [(0, 0, 0), (1, 0, 0), (0, 1, 0)],
                100: [(0, 0, 1), (1, 0, 1), (0, 1, 1)],
            }
        }
    }
}
""")
flat = Usd.Stage.Open(os.path.join(HERE, "shot.usda")).Flatten()
flat.documentation = "Usd.Stage.Open('shot.usda').Flatten(), by make.py"
flat.Export(os.path.join(HERE, "shot.flat.usda"))

Sdf.Layer.FindOrOpen(os.path.join(BLENDER, "tumble_thick.usda")).Export(
    os.path.join(HERE, "tumble_thick_crate.usd"), args={"format": "usdc"})
Sdf.Layer.FindOrOpen(os.path.join(BLENDER, "tumble_thick_rigged.usda")).Export(
    os.path.join(HERE, "tumble_thick_rigged.usdc"))
Sdf.Layer.FindOrOpen(os.path.join(HERE, "..", "skinned_leaf.usda")).Export(
    os.path.join(HERE, "skinned_leaf.usdc"))
crate = os.path.join(HERE, "tumble_thick.usdc")
Sdf.Layer.FindOrOpen(os.path.join(BLENDER, "tumble_thick.usda")).Export(crate)
UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(crate), os.path.join(HERE, "tumble_thick.usdz"))
os.remove(crate)
