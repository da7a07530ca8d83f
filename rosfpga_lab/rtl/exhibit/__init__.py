"""The exhibit: the hand-written ``sensor_msgs/Image`` circuit, the conventional design of the
paper's Table 1 (see ``README.md`` here). No tool of the library imports it; its test and
:mod:`rosfpga_lab.rtl.sloc`'s line count read it."""
