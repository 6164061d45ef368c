"""A scene as the front doors take it: a :class:`Scene`, a scene file's path or a bundled name."""

from __future__ import annotations

import os

from cable_ocp.scene.bundled import scene_argument
from cable_ocp.scene.schema import Scene, load_scene


def scene_given(scene: Scene | str | os.PathLike, what: str) -> Scene:
    """The scene ``what`` (a front door's name, e.g. ``"optimize"``) was given, loaded if need be.

    Parameters
    ----------
    scene : Scene, str or path-like
        A scene, or what the command line takes: a scene file's path or a bundled scene's name
        (``"paper_hill"``), loaded by :func:`~cable_ocp.scene.schema.load_scene`.
    what : str
        The function that takes it, named in the error.

    Raises
    ------
    TypeError
        Anything else, naming what is accepted.
    SceneError
        A path that is not a valid scene file (naming the file, or the field).
    """
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, str | os.PathLike):
        return load_scene(scene_argument(os.fspath(scene)))
    raise TypeError(
        f"{what}: scene must be a Scene (co.load_scene(...)), a scene file's path or a bundled "
        f"scene's name; got {type(scene).__name__}"
    )
