"""Self-contained HTML report (inline CSS and SVG; no external requests).

The page is rendered from :func:`toolbox.report.build_context` with a jinja2
template (``templates/report.html.j2``) under autoescaping, so every string
from the spec, the artifact or the caller is shown literally. Figures are SVG
produced by :mod:`toolbox.report.plots` (trusted, generated here, free of user
text) and are the only values marked safe.
"""

from __future__ import annotations

from pathlib import Path

import jinja2

from .._cache import template_bytecode_cache
from . import build_context

__all__ = ["write_html", "render_html"]

TEMPLATES = Path(__file__).parent / "templates"


def _environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES)),
        bytecode_cache=template_bytecode_cache(__file__),
        autoescape=True,  # every template, whatever its extension
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )


def render_html(context: dict) -> str:
    """Render a content model (see :func:`toolbox.report.build_context`) to HTML text."""
    return _environment().get_template("report.html.j2").render(**context)


def write_html(data) -> str:
    """The HTML report of ``data``.

    Parameters
    ----------
    data : toolbox.report.ReportData or dict
        The report's data, or its content model from
        :func:`toolbox.report.build_context` (to share figures with the PDF).

    Returns
    -------
    str
        A complete HTML5 document (UTF-8 text) that makes no network request:
        CSS and figures are inline. Identical inputs give identical text
        (the only time stamps are the artifact's provenance and
        ``data.generated``). Writing it to disk (atomically) is the caller's job.
    """
    return render_html(data if isinstance(data, dict) else build_context(data))
