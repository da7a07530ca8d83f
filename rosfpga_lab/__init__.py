"""rosfpga_lab: rebuild a ROS-compliant FPGA component, byte for byte, in Python.

The package is layered (``ARCHITECTURE.md`` in the repository: the layers, the conventions, the
commands): ``errors`` -> ``msg`` -> ``tcpros``/``rtps`` -> ``config`` -> ``graph`` -> ``hw`` ->
``hls`` -> ``rtl`` -> ``component`` -> ``widgets``/``checks`` -> ``bench`` -> ``cli``. A layer
imports only the layers below it (``tests/flow/test_layers.py``).
"""

from rosfpga_lab.errors import LabError

__all__ = ["LabError", "__version__"]
__version__ = "0.1.0"
