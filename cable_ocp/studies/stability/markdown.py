"""Markdown helpers of the stability report."""

from __future__ import annotations


def table_cell(text: str) -> str:
    """Text safe inside a markdown table cell (``|`` escaped)."""
    return text.replace("|", "\\|")
