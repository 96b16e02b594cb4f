"""Firmware export: the controller artifact as a C99 header (``controller.h``).

``write_header(artifact, motor=None, drive=None, *, prefix="cct_") -> str`` and
``check_exportable(artifact, ...)`` (refuses unstable or ill-conditioned
controllers, and constants out of float32/C ranges, with
:class:`toolbox.errors.ExportRefused`); see
:mod:`toolbox.export.c_header` for the header layout and the rules.
"""

from .c_header import (ExportCheck, ReferenceLaw, check_exportable, example_source,
                       prefix_name, reference_law, sanitise_comment, write_header)

__all__ = ["write_header", "check_exportable", "ExportCheck", "ReferenceLaw",
           "reference_law", "sanitise_comment", "prefix_name", "example_source"]
