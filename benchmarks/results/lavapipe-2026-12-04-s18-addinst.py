import time, warnings
warnings.simplefilter("ignore")
import numpy as np
from pathlib import Path
from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene
scene = load_scene(Path("/work/shared/assets/CesiumMan/glTF/CesiumMan.gltf"))
r = Renderer(scene)
mesh = next(n.mesh for n in scene.nodes if n.mesh is not None and n.mesh >= 0)
m = np.tile(np.eye(4), (1000, 1, 1)); m[:, 0, 3] = np.arange(1000)
t = time.perf_counter(); r.add_instances(mesh, m); dt = time.perf_counter() - t
print(f"add_instances(1000 CesiumMan): {dt:.2f} s")
r.close()
