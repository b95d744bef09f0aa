"""Small HTML helpers of the report page: escaping, number and time formats, inline images.

Every string that comes from a file goes through :func:`esc` (:func:`html.escape`, quotes too,
after :func:`visible`: control, format and other unprintable characters, such as NUL, ESC or a
right-to-left override, U+202E, which would reorder what a reader sees, shown as escapes).
"""

from __future__ import annotations

import base64
import math
import time
from html import escape
from typing import Any

from fuzzer.reporting import shown


def visible(text: str) -> str:
    """``text`` with its unprintable characters but line breaks and tabs as Python escapes
    (``\\x1b``, ``\\u202e``), so that a sidecar's string shows what it holds."""
    return shown(text, "\n\t")


def esc(value: Any) -> str:
    return escape(visible(str(value)), quote=True)


def pct(x: float | None) -> str:
    return "n/a" if x is None else f"{100 * x:.2f}%"


def num(v: float) -> str:
    return f"{v:.10g}" if math.isfinite(v) else str(v)


def utc(t: float | None) -> str:
    return "n/a" if t is None else time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(t))


def img(png: bytes, alt: str) -> str:
    data = base64.b64encode(png).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{esc(alt)}">'


def figure(png: bytes | None, alt: str, caption: str, missing: str) -> str:
    if png is None:
        return f'<p class="note">{esc(missing)}</p>'
    return f"<figure>{img(png, alt)}<figcaption>{caption}</figcaption></figure>"


def kind_class(kind: str) -> str:
    return f"k-{kind}" if kind in ("crash", "status", "value", "representation") else "k-other"
