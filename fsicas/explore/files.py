"""Scene files on the explorer's page: read as the command line reads them, their values
written into the page's address and read back from it, the preset a physical file is."""
from __future__ import annotations

import base64
import json
import tempfile
from pathlib import Path

from ..checks import read_toml
from ..physical import Physical, load_physical, preset_names
from ..scene import Scene

__all__ = ["read_scene_file", "encode_file", "decode_file", "matching_preset"]


def read_scene_file(name: str, data: bytes) -> Scene | Physical:
    """The scene file ``name`` with the content ``data``, read by the library as the CLI
    reads it: a file with a ``[physical]`` table (or ``preset = NAME``) as ``--physical
    FILE.toml`` (``load_physical``), any other as ``--scene FILE.toml``
    (``Scene.from_dict`` of ``read_toml``, as ``load_scene``); their ValueError, naming
    the file by its name."""
    name = Path(str(name)).name or "scene.toml"
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / name
        path.write_bytes(data)
        try:
            doc = read_toml(path, "scene file")
            if "physical" in doc or "preset" in doc:
                return load_physical(str(path))
            return Scene.from_dict(doc)
        except ValueError as err:
            raise ValueError(str(err).replace(folder + "/", "")) from None


def encode_file(read: Scene | Physical) -> str:
    """The values of a loaded scene file as a string for the page's address: the Scene's
    fields (``Scene.to_dict``), or a physical file's [physical] table as written, its
    Scene fields and description; compact JSON in URL-safe base64."""
    if isinstance(read, Physical):
        doc = {"physical": read.raw, "fields": read.scene_fields,
               "description": read.description}
    else:
        doc = {"scene": read.to_dict()}
    text = json.dumps(doc, separators=(",", ":"), allow_nan=False)
    return base64.urlsafe_b64encode(text.encode()).decode().rstrip("=")


def decode_file(name: str, data: str) -> Scene | Physical:
    """The scene file ``name`` of :func:`encode_file`'s ``data``, read by the library
    (``Scene.from_dict``, or ``Physical.from_table`` as ``load_physical`` does); a
    ValueError naming the address where it is not such a string."""
    try:
        doc = json.loads(base64.urlsafe_b64decode(data + "=" * (-len(data) % 4)))
        if not isinstance(doc, dict) or not ({"scene"} == set(doc) or "physical" in doc):
            raise ValueError
    except ValueError:
        raise ValueError(f"the address's scene (scene file {name}) is not a scene written "
                         "by this page") from None
    if "scene" in doc:
        return Scene.from_dict(doc["scene"])
    return Physical.from_table(doc["physical"], name, str(doc.get("description", "")),
                               doc.get("fields", {}))


def matching_preset(physical: Physical) -> str | None:
    """The preset whose values ``physical`` has (its table and Scene fields), or None."""
    for name in preset_names():
        preset = load_physical(name)
        if (preset.raw, preset.scene_fields) == (physical.raw, physical.scene_fields):
            return name
    return None
