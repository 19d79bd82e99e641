"""Imported before PyTorch (the sb3 library): hides Triton from this process.

PyTorch imports Triton (torch.compile's GPU kernel compiler) the first time an optimizer is built,
wherever Triton is installed (PyPI's Linux torch wheels bring it). In a process that has opened an
EGL context (MuJoCo's offscreen renderer: videos, the dashboard's frames, the render tests),
loading Triton's library crashes it (segmentation fault; seen with torch 2.15 + triton 3.9 on a CPU
machine: `python -m pytest` lost a worker and then hung). SB3 never compiles with Triton, so it is
hidden: `import triton` raises ImportError and PyTorch takes it as not installed. A process that
imported Triton before keeps it.
"""

import sys

sys.modules.setdefault("triton", None)
