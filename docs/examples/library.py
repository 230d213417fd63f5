"""Bakes the default scene in-process and checks it against `fractalbake render`, bit for bit.
    python3 docs/examples/library.py [FRACTALBAKE]        (the program: `fractalbake` on PATH)"""
import subprocess
import sys
import tempfile

import numpy as np

import fractalbake

program = sys.argv[1] if len(sys.argv) > 1 else "fractalbake"
planes = fractalbake.render(backend="native")  # {"sky.R": array, ...}, as the EXR's channels
with tempfile.TemporaryDirectory() as tmp:
    subprocess.run([program, "render", "--backend", "native", "-q", "-o", f"{tmp}/cli.exr"], check=True)
    cli = fractalbake.read(f"{tmp}/cli.exr")
same = sorted(cli) == sorted(planes) and all(
    cli[k].dtype == planes[k].dtype and cli[k].tobytes() == planes[k].tobytes() for k in cli)
sky = np.stack([planes[c] for c in ("sky.R", "sky.G", "sky.B")], axis=-1)
print(f"{len(planes)} channels, {sky.shape[1]} x {sky.shape[0]}, mean sky {sky.astype(np.float32).mean():.4f};",
      "the same bits as fractalbake render" if same else "DIFFERENT from fractalbake render")
sys.exit(0 if same else 1)
