"""Frame-path queries: frames_between and find_frame."""

from __future__ import annotations

import pytest

import rbm_nb as rbm
from rbm_nb._door.frame_paths import frame_path
from rbm_nb.core.frames import ReferenceFrame, find_frame, frames_between


@pytest.fixture
def tree():
    """world(registered) -> head -> left_eye, right_eye; world -> body -> left_hand
    -> left_eye (a second frame of that name, deeper); lab (registered, own tree)."""
    world = ReferenceFrame("world")
    world.register()
    head = ReferenceFrame("head", parent=world)
    ReferenceFrame("left_eye", parent=head)
    ReferenceFrame("right_eye", parent=head)
    body = ReferenceFrame("body", parent=world)
    hand = ReferenceFrame("left_hand", parent=body)
    ReferenceFrame("left_eye", parent=hand)  # a camera on the hand
    lab = ReferenceFrame("lab")
    lab.register()
    ReferenceFrame("tracker", parent=lab)
    return world


def names(frames):
    return [f.name for f in frames]


# ---------------------------------------------------------------------------
# frames_between
# ---------------------------------------------------------------------------


def test_frames_between_goes_up_then_down(tree):
    eye = find_frame("head/left_eye")
    hand = find_frame("left_hand")
    assert names(frames_between(eye, hand)) == [
        "left_eye",
        "head",
        "world",
        "body",
        "left_hand",
    ]
    assert names(frames_between(eye, "world")) == ["left_eye", "head", "world"]
    assert names(frames_between("world", eye)) == ["world", "head", "left_eye"]
    assert names(frames_between(eye, eye)) == ["left_eye"]
    sibling = find_frame("right_eye")
    assert names(frames_between(eye, sibling)) == ["left_eye", "head", "right_eye"]


def test_frames_between_end_flags(tree):
    eye = find_frame("head/left_eye")
    assert names(frames_between(eye, "world", include_self=False)) == ["head", "world"]
    assert names(frames_between(eye, "world", include_to_frame=False)) == [
        "left_eye",
        "head",
    ]
    assert names(
        frames_between(eye, "world", include_self=False, include_to_frame=False)
    ) == ["head"]
    assert frames_between(eye, eye, include_self=False) == ()


def test_frames_between_matches_the_transform_chain(tree):
    """The frames a lookup composes are exactly the chain between the ends."""
    from rbm_nb._engine.chain import chain

    eye = find_frame("head/left_eye")
    hand = find_frame("left_hand")
    steps = chain(eye, hand)
    between = frames_between(eye, hand)
    up = [f for f, inverse in steps if not inverse]
    down = [f for f, inverse in steps if inverse]
    # the engine's steps are the frames' values
    assert [f.data for f in between[: len(up)]] == up
    assert [f.data for f in between[-len(down) :]] == down


def test_frames_between_different_trees(tree):
    with pytest.raises(
        ValueError, match=r"different trees \(roots 'world' and 'lab'\)"
    ):
        frames_between("world", "lab")
    with pytest.raises(ValueError, match="not found in registry"):
        frames_between("world", "nowhere")


# ---------------------------------------------------------------------------
# find_frame
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "path,expected",
    [
        ("world/head/left_eye", "world/head/left_eye"),
        ("head/left_eye", "world/head/left_eye"),
        ("world/*/left_eye", "world/head/left_eye"),
        ("left_hand/left_eye", "world/body/left_hand/left_eye"),
        ("body/.../left_eye", "world/body/left_hand/left_eye"),
        ("world/.../left_hand/left_eye", "world/body/left_hand/left_eye"),
        ("/world", "world"),
        ("/.../right_eye", "world/head/right_eye"),
        ("right_*", "world/head/right_eye"),
        ("lab/tracker", "lab/tracker"),
        ("/lab/trac?er", "lab/tracker"),
        ("world/b[aeiou]dy", "world/body"),
    ],
)
def test_find_frame_paths(tree, path, expected):
    assert frame_path(find_frame(path)) == expected


def test_ellipsis_needs_at_least_one_link(tree):
    # '...' is a chain: 'head/.../left_eye' also finds the direct child
    assert frame_path(find_frame("head/.../left_eye")) == "world/head/left_eye"
    with pytest.raises(ValueError, match="no frame matches"):
        find_frame("left_eye/.../left_eye")


def test_several_matches_are_listed(tree):
    with pytest.raises(ValueError) as info:
        find_frame("world/.../left_eye")
    msg = str(info.value)
    assert msg.startswith("2 frames match the path 'world/.../left_eye'")
    assert "'world/head/left_eye'" in msg and "'world/body/left_hand/left_eye'" in msg
    with pytest.raises(ValueError, match="3 frames match"):
        find_frame("*_eye")


def test_no_match_suggests_close_names(tree):
    with pytest.raises(ValueError, match=r"close names: 'world/body/left_hand'"):
        find_frame("world/left_hnd")
    with pytest.raises(
        ValueError,
        match=r"no frame matches the path '/head'; close names: 'world/head'",
    ):
        find_frame("/head")
    with pytest.raises(ValueError, match=r"\(frames: 'world', 'world/head'"):
        find_frame("zzzzzz")


def test_bad_paths(tree):
    with pytest.raises(ValueError, match="empty element"):
        find_frame("world//head")
    with pytest.raises(ValueError, match="must end with a frame name"):
        find_frame("world/...")
    with pytest.raises(ValueError, match="names no frame"):
        find_frame("...")
    with pytest.raises(ValueError, match="must be a string"):
        find_frame(3)


def test_empty_registry():
    rbm.clear_registry()
    with pytest.raises(ValueError, match="the registry is empty"):
        find_frame("world")


def test_unregistered_trees_are_not_searched():
    root = ReferenceFrame("hidden_root")
    ReferenceFrame("hidden", parent=root)
    with pytest.raises(ValueError, match="registry is empty"):
        find_frame("hidden")


def test_docstring_examples_run():
    import doctest
    import importlib

    module = importlib.import_module("rbm_nb._door.frame_paths")
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0


def test_public_wiring(tree):
    eye = rbm.find_frame("head/left_eye")
    assert eye is find_frame("head/left_eye")
    hand = rbm.find_frame("left_hand")
    assert eye.frames_between(hand) == frames_between(eye, hand)
    assert names(eye.frames_between("world", include_self=False)) == ["head", "world"]
