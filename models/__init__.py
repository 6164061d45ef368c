"""Bundled scene files, installed as the data package ``cable_ocp.models`` (cable_ocp.bundled)."""
