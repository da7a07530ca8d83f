"""rosfpga_lab: rebuild a ROS-compliant FPGA component, byte for byte, in Python.

The package is layered (see ``DESIGN.md`` in the course material and the README):
``msg`` -> ``tcpros`` -> ``config`` -> ``graph`` -> ``hw`` -> ``hls`` -> ``component`` -> ``widgets``/``checks``
-> ``cli``. A layer imports only the layers below it.
"""

from rosfpga_lab.errors import LabError

__all__ = ["LabError", "__version__"]
__version__ = "0.1.0"
