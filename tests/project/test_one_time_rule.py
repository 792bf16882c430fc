"""One time rule: only rbm_nb._engine.time turns datetime64 into numbers.

Every module of the package that needs seconds, keys or epoch floats from
datetime64/timedelta64 values asks the time module (``as_track``,
``TimeBase``, ``epoch_seconds``), so there is one conversion, one ordering
rule and one set of messages. This test reads the AST of every module and
fails on a conversion written anywhere else:

* ``x.astype(np.int64)`` (or ``"int64"``, ``int``) where ``x`` is a time:
  a datetime64/timedelta64 cast or a name that says so (``stamps``,
  ``times``, ``t0_ns``...);
* ``x.view(np.int64)`` / ``x.view("int64")`` (the ns behind a datetime64);
* ``x / np.timedelta64(1, unit)`` (a duration as a number).
"""

from __future__ import annotations

import ast
from pathlib import Path

from conftest import REPO

PACKAGE = REPO / "rbm_nb"

#: The time module itself, and the kernels it calls.
OWNERS = {"rbm_nb/_engine/time.py", "rbm_nb/_kernels/times.py"}

#: Conversions that are not about a time value (with the reason).
NOT_TIME: set[str] = set()

_TIME_TOKENS = {"ts", "ns", "t0", "stamp", "stamps", "timestamp", "timestamps"}
_INT_NAMES = {"int64", "int", "uint64"}


def _text(node: ast.AST) -> str:
    return ast.unparse(node)


def _is_int_dtype(node: ast.AST) -> bool:
    text = _text(node).strip("'\"")
    last = text.rsplit(".", 1)[-1]
    return last in _INT_NAMES


def _words(node: ast.AST) -> list[str]:
    """The names, attributes and strings an expression is made of."""
    out = []
    for sub in ast.walk(node):
        if isinstance(sub, ast.Name):
            out.append(sub.id)
        elif isinstance(sub, ast.Attribute):
            out.append(sub.attr)
        elif isinstance(sub, ast.Constant) and isinstance(sub.value, str):
            out.append(sub.value)
    return [w.lower() for w in out]


def _mentions_time(node: ast.AST) -> bool:
    """Whether an expression is about times: a time cast, or a time-like name."""
    for word in _words(node):
        if "datetime64" in word or "timedelta64" in word or "time" in word:
            return True
        if any(token in _TIME_TOKENS for token in word.split("_")):
            return True
    return False


def conversions(path: Path) -> list[str]:
    """``line: source`` of each datetime64-to-number conversion in ``path``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            method = node.func.attr
            receiver = node.func.value
            args = node.args
            if method == "astype" and args:
                if _is_int_dtype(args[0]) and _mentions_time(receiver):
                    found.append(f"{node.lineno}: {_text(node)}")
            elif method == "view" and args and _is_int_dtype(args[0]):
                found.append(f"{node.lineno}: {_text(node)}")
        elif (
            isinstance(node, ast.BinOp)
            and isinstance(node.op, (ast.Div, ast.FloorDiv))
            and isinstance(node.right, ast.Call)
            and _text(node.right.func).endswith("timedelta64")
        ):
            found.append(f"{node.lineno}: {_text(node)}")
    return found


def test_only_the_time_module_converts_datetimes_to_numbers():
    offenders = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(REPO).as_posix()
        if rel in OWNERS or rel in NOT_TIME:
            continue
        found = conversions(path)
        if found:
            offenders[rel] = found
    assert not offenders, (
        "datetime64 converted to numbers outside rbm_nb/_engine/time.py "
        "(use as_track / TimeBase / epoch_seconds):\n"
        + "\n".join(f"  {k}: {v}" for k, v in offenders.items())
    )


def test_the_check_finds_each_form(tmp_path):
    """The AST check sees every form it claims to (so an empty result means something)."""
    sample = tmp_path / "sample.py"
    sample.write_text(
        "import numpy as np\n"
        "a = stamps.astype('datetime64[ns]').astype(np.int64)\n"
        "b = times.astype(np.int64)\n"
        "c = key.view(np.int64)\n"
        "d = span / np.timedelta64(1, 'ns')\n"
        "e = counts.astype(np.int64)\n"  # not a time: no finding
        "f = x.astype(float)\n"
        "g = np.linspace(0, 9, 5).round().astype(np.int64)\n"
        "h = stamps_ns.astype('datetime64[ns]')\n",
        encoding="utf-8",
    )
    lines = [f.split(":")[0] for f in conversions(sample)]
    assert lines == ["2", "3", "4", "5"]
