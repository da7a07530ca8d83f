"""Subscriber and publisher models of any message type, rendered from its circuit layout.

The subscriber (:class:`LayoutInterpreter`, :func:`extract_reference`, :func:`extract_fast`) is
:mod:`rosfpga_lab.hw.subscriberwalker`; the publisher (:func:`publish_reference`,
:func:`publish_fast`) is :mod:`rosfpga_lab.hw.publisherwalker`. This module gathers their
public names, the import the tests and the HLS renderer use.
"""

from __future__ import annotations

from rosfpga_lab.hw.publisherwalker import (
    message_of, output_tokens, publish_fast, publish_reference, published_tokens, shift_out,
    value_size, write_value,
)
from rosfpga_lab.hw.subscriberwalker import (
    STAGE, Extracted, LayoutInterpreter, extract_fast, extract_reference, run_fast,
    run_reference,
)

__all__ = [
    "STAGE", "Extracted", "LayoutInterpreter", "extract_fast", "extract_reference", "message_of",
    "output_tokens", "publish_fast", "publish_reference", "published_tokens", "run_fast",
    "run_reference", "shift_out", "value_size", "write_value",
]
