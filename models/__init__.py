"""Bundled scene files, installed as the data package ``cable_ocp.models``.

Found by :mod:`cable_ocp.scene.bundled`.
"""
