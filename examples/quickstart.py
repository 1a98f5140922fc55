"""vdiso from Python in ten lines: a NumPy volume to a store, its visible surface, a picture, a GLB.
Run from the repository root:  PYTHONPATH=build/python /usr/bin/python3 examples/quickstart.py [OUT_DIR]"""
import os, sys
import numpy as np
import vdiso

out = sys.argv[1] if len(sys.argv) > 1 else "."
z, y, x = np.mgrid[:96, :128, :128].astype(np.float32)
volume = (1000 - 8 * np.sqrt((x - 64) ** 2 + (y - 64) ** 2 + (1.3 * (z - 48)) ** 2)).clip(0).astype(np.uint16)

vdiso.convert(volume, os.path.join(out, "ball.vdiso"), spacing=(1.3, 1.0, 1.0), overwrite=True)
store = vdiso.open(os.path.join(out, "ball.vdiso"))
mesh = store.extract(500, method="sage", view="normal")        # what the camera sees
image = store.render(500, size=(400, 300))                     # (300, 400, 3) uint8, for plt.imshow
mesh.write(os.path.join(out, "ball.glb"), overwrite=True)
verts, faces, normals, values = vdiso.marching_cubes(volume, 500, spacing=(1.3, 1.0, 1.0))  # as scikit-image
print(f"{store}: {len(mesh.faces)} visible triangles of {len(faces)}; image {image.shape}")
