"""Untrusted text shown in the explorer: always as literal text, never as markup.

viser's markdown panels render raw HTML (``add_markdown`` is not sanitised), so any value that
comes from a URL, a form, a request or a job's error message must be escaped before it is put into
one. :func:`md_text` turns a value into markdown that renders as exactly its characters:

* every ASCII punctuation character gets a backslash (CommonMark 0.31, §2.4 "Backslash escapes":
  *any* ASCII punctuation may be escaped and is then a literal character), which disarms HTML tags
  (``\\<``), entities (``\\&``), links and images (``\\[``, ``\\!``), emphasis, code spans, tables
  and autolinks (``\\:`` breaks ``http://``);
* line breaks and other control characters fold to single spaces, so a value cannot open a block
  (heading, list, quote, fence);
* the length is bounded (``max_chars``, with an ellipsis), so a value cannot flood the panel.

The explorer's own texts (labels, numbers it formats) are markdown written by us; every value from
outside goes through this function first.
"""

from __future__ import annotations

import string

__all__ = ["md_text", "plain_text"]

_PUNCT = frozenset(string.punctuation)


def plain_text(value: object, max_chars: int = 300) -> str:
    """``str(value)`` with control characters and line breaks folded to spaces, at most
    ``max_chars`` characters (an ellipsis marks a cut)."""
    text = "".join(" " if (ord(ch) < 32 or 0x7F <= ord(ch) < 0xA0 or ch in "\u2028\u2029") else ch
                   for ch in str(value))
    text = " ".join(text.split())
    if len(text) > max_chars:
        text = text[: max(0, max_chars - 1)] + "…"
    return text


def md_text(value: object, max_chars: int = 300) -> str:
    """Markdown that renders as the literal text of ``value`` (see the module docstring)."""
    return "".join("\\" + ch if ch in _PUNCT else ch for ch in plain_text(value, max_chars))
