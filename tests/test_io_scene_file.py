"""Scene files (wavecontact.io.scene_file): the schema of docs/usage.md to a Scene, refusals in one line."""

import json
import math

import pytest

from wavecontact import Hard, PiecewiseRod, RigidBody, Rod
from wavecontact.errors import InvalidParameterError
from wavecontact.io.scene_file import read_scene_file

HAMMER = """
[contact]
law = "hard"

[[body]]
mass = 2.0
velocity = 1.0

[[body]]
length = 1.0

[[body]]
[[body.segment]]
length = 1.0
[[body.segment]]
length = 0.5
area = 2.0
end_area = 1.0
"""


def write(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_toml_builds_the_bodies_from_left_to_right(tmp_path):
    read = read_scene_file(write(tmp_path, HAMMER))
    scene = read.scene
    assert isinstance(scene.rods[0], RigidBody) and scene.rods[0].mass == 2.0
    assert isinstance(scene.rods[1], Rod) and scene.rods[1].length == 1.0
    assert isinstance(scene.rods[2], PiecewiseRod) and len(scene.rods[2].segments) == 2
    assert scene.velocities == (1.0, 0.0, 0.0)
    assert read.names == ("body0", "body1", "body2") and read.solver is None


def test_json_is_the_same_schema(tmp_path):
    import tomllib

    data = tomllib.loads(HAMMER)
    toml_scene = read_scene_file(write(tmp_path, HAMMER)).scene
    json_scene = read_scene_file(write(tmp_path, json.dumps(data), "scene.json")).scene
    assert json_scene == toml_scene


def test_per_pair_contacts_walls_and_solve_table(tmp_path):
    text = HAMMER.replace('[contact]\nlaw = "hard"\n', '''
gaps = [0.0, 0.5]
[solve]
solver = "fem"
elements = 64
[[contact]]
law = "hard"
[[contact]]
law = "exponential"
alpha = 50.0
[walls.right]
gap = 0.25
''')
    read = read_scene_file(write(tmp_path, text))
    assert read.solver == "fem" and read.options == {"elements": 64}
    assert read.scene.gaps == (0.0, 0.5)
    assert isinstance(read.scene.contact[0], Hard) and read.scene.contact[1].alpha == 50.0
    assert read.scene.walls[0] is None and read.scene.walls[1].gap == 0.25


@pytest.mark.parametrize("old, new, words", [
    ("length = 1.0\n\n[[body]]\n[[body.segment]]", "lenght = 1.0\n\n[[body]]\n[[body.segment]]", ["body[1].lenght", "unknown key"]),
    ('law = "hard"', 'law = "sticky"', ["contact.law", "sticky"]),
    ("mass = 2.0", "mass = -2.0", ["body[0]", "mass"]),
    ("length = 0.5", "length = 0.0", ["body[2].segment[1]", "length"]),
    ("end_area = 1.0", "end_area = 0.0", ["body[2].segment[1]", "end_area"]),
    ("velocity = 1.0", 'velocity = "fast"', ["body[0].velocity", "fast"]),
    ("mass = 2.0", "mass = 2.0\nlength = 1.0", ["body[0].length", "unknown key"]),
    ('law = "hard"', 'law = "hard"\nalpha = 3.0', ["contact.alpha", "unknown key"]),
    ("[contact]", "gaps = [-1.0, 0.0]\n[contact]", ["gaps[0]", ">= 0", "overlap"]),
    ("[contact]", "gaps = [0.0]\n[contact]", ["gaps"]),
    ("velocity = 1.0", "velocity = 1.0\n[body.segment]", ["body[0]", "segment"]),
    ('[contact]', 'x = = 1\n[contact]', ["not valid TOML"]),
])
def test_bad_files_are_refused_naming_the_file_and_the_key(tmp_path, old, new, words):
    assert old in HAMMER
    path = write(tmp_path, HAMMER.replace(old, new, 1))
    with pytest.raises(InvalidParameterError) as info:
        read_scene_file(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(path)), message
    for word in words:
        assert word in message, (word, message)


def test_a_file_without_bodies_or_of_another_kind(tmp_path):
    for name, text, word in (("a.toml", "title = 'x'", "body"), ("a.yaml", "x: 1", ".toml or .json"),
                             ("a.json", "[1, 2]", "table"), ("b.toml", "[[body]]\nmass = 1.0", "wall")):
        with pytest.raises(InvalidParameterError, match=word):
            read_scene_file(write(tmp_path, text, name))


def test_every_example_scene_file_reads(tmp_path):
    from pathlib import Path

    files = sorted((Path(__file__).resolve().parent.parent / "examples" / "scenes").glob("*.*"))
    assert len(files) >= 4
    for path in files:
        read = read_scene_file(path)
        assert read.title and read.solver == "fem"
        assert math.isfinite(sum(getattr(b, "mass", math.nan) for b in read.scene.rods))


def test_the_example_in_docs_usage_reads(tmp_path):
    """The TOML example of docs/usage.md, "Scene files", is a valid scene file."""
    import re
    from pathlib import Path

    usage = (Path(__file__).resolve().parent.parent / "docs" / "usage.md").read_text()
    section = usage[usage.index("### Scene files"):]
    (block,) = re.findall(r"```toml\n(.*?)```", section[:section.index("### Every option")], re.DOTALL)
    read = read_scene_file(write(tmp_path, block))
    assert isinstance(read.scene.rods[0], RigidBody) and read.names == ("hammer", "bar")
