# Compares meshlight's image of a Blender export with Cycles' (run in Blender's Python, whose
# image loader reads both EXRs): the means, and MAE/mean per pixel and over 4 x 4 blocks, ours
# averaged down to Cycles' size first.
#   meshlight render /tmp/room.glb -o /tmp/ours.exr
#   /tmp/bpy-venv/bin/python scripts/compare_with_cycles.py -- /tmp/room-cycles.exr /tmp/ours.exr
import bpy, numpy as np, sys
def load(p):
    im = bpy.data.images.load(p)
    w, h = im.size
    a = np.array(im.pixels[:], dtype=np.float64).reshape(h, w, 4)[:, :, :3]
    return a
ref = load(sys.argv[sys.argv.index("--") + 1])
ours = load(sys.argv[sys.argv.index("--") + 2])
f = ours.shape[0] // ref.shape[0]
ours = ours.reshape(ref.shape[0], f, ref.shape[1], f, 3).mean(axis=(1, 3))
print("mean cycles %.5f ours %.5f ratio %.4f" % (ref.mean(), ours.mean(), ours.mean() / ref.mean()))
print("MAE/mean %.4f" % (np.abs(ours - ref).mean() / ref.mean()))
b = lambda a: a.reshape(a.shape[0] // 4, 4, a.shape[1] // 4, 4, 3).mean(axis=(1, 3))
print("MAE/mean over 4x4 blocks %.4f" % (np.abs(b(ours) - b(ref)).mean() / ref.mean()))
