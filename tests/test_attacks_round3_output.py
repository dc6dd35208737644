"""Hostile submissions against what grading shows (issue 34, round three): what a student sees, and what the
grader holds while it reads an answer.

- A one-bit oracle on hidden tests: two submissions that differ only in whether they pass a hidden test must
  get the same visible results (messages, scores, dependency notes, totals, times), in every layout a student
  sees before grades are published.
- Control characters: what a submission prints, raises, answers or names reaches no terminal, gradebook,
  results.json, report or Classroom step as raw escape sequences, bidi overrides or other controls; it is
  shown escaped (``\x1b``), in every layout.
- Memory before refusal: an answer too large is refused from its headers, unread, and the grader holds at most
  one answer per worker, each read once, in place.

Submissions are built at run time in a temporary folder; those that must fail a hidden case recognise it by
its own arguments (taken from ``hidden.py`` here), so the attack holds whatever cases the public tests use.
"""
from __future__ import annotations

import csv
import io
import json
import os
import re
import shutil
import subprocess
import sys
import unicodedata
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.grading import sandbox
from cs451.grading.loader import load_tests
from cs451.grading.report import render_report
from cs451.grading.results import format_table, to_gradescope, total_score
from cs451.grading.roster import grade_roster
from cs451.grading.runner import grade
from cs451.packaging.release import build_release

from conftest import world_readable_dir
from test_attacks import attack
from test_packaging import run_autograder

pytestmark = pytest.mark.skipif(not sandbox.is_root(), reason="the attacks are graded as a root grader grades them")


def _params(stage: str, number: str) -> dict:
    return next(t.params for t in load_tests(stage) if t.number == number)


def _package(root: Path, stage: str, tail: str) -> Path:
    """The reference's package of ``stage`` with ``tail`` appended to its ``__init__.py``, readable by the sandbox."""
    shutil.copytree(KIT_ROOT / "reference" / stage, root / stage, ignore=shutil.ignore_patterns("__pycache__"))
    init = root / stage / "__init__.py"
    init.write_text(init.read_text() + tail)
    for path in [root, *root.rglob("*")]:
        path.chmod(0o755 if path.is_dir() else 0o644)
    return root


def seen_before_publication(data: dict) -> dict:
    """What a student sees of a results.json before grades are published: all but the tests not yet visible."""
    return {**{k: v for k, v in data.items() if k != "tests"},
            "tests": [t for t in data["tests"] if t.get("visibility", "visible") == "visible"]}


def table_without_hidden_rows(table: str) -> str:
    """``cs451 grade``'s table less the hidden tests' rows (with their messages) and the line that counts them."""
    kept, skipping = [], False
    for line in table.splitlines():
        if line.startswith(" "):
            if not skipping:
                kept.append(line)
            continue
        skipping = "[hidden]" in line or line.startswith("total with the hidden tests")
        if not skipping:
            kept.append(line)
    return "\n".join(kept)


# --- item 4: a one-bit oracle on hidden tests ----------------------------------------------------------

RADIOSITY_ORACLE = '''

import numpy as _np
from .patches import subdivide as _right_subdivide
from .shooting import shoot as _right_shoot

_HIDDEN_SHOT = {shot}
_HIDDEN_GRID = {grid}
_PASS_HIDDEN_SHOT = {pass_shot}
_PASS_HIDDEN_GRID = {pass_grid}


def _same(a, b):
    a, b = _np.asarray(a, float), _np.asarray(b, float)
    return a.shape == b.shape and _np.allclose(a, b)


def shoot(i, row, areas, reflectance, radiosity, unshot):
    """Right, except on the hidden case when told to fail it."""
    B, dB = _right_shoot(i, row, areas, reflectance, radiosity, unshot)
    hidden = i == _HIDDEN_SHOT["i"] and _same(areas, _HIDDEN_SHOT["areas"])
    return (B if _PASS_HIDDEN_SHOT or not hidden else _np.zeros_like(B)), dB


def subdivide(quads, max_edge):
    """Right where the answer is to do nothing (the edge case) and on the hidden case when told; else nothing."""
    hidden = max_edge == _HIDDEN_GRID["max_edge"] and _same(quads, _HIDDEN_GRID["quads"])
    if max_edge <= 0 or (hidden and _PASS_HIDDEN_GRID):
        return _right_subdivide(quads, max_edge)
    q = _np.asarray(quads, float)
    return q.copy(), _np.arange(len(q))


def progressive_refinement(row, areas, reflectance, emission, tolerance, max_shots, overshoot, on_shot):
    """Wrong everywhere: its failing tests name R2 shoot(), which they rely on."""
    E = _np.array(emission, float)
    return E, _np.zeros_like(E), []
'''


def radiosity_oracle(root: Path, pass_hidden_shot: bool, pass_hidden_grid: bool) -> Path:
    """A radiosity submission whose hidden R2.3 (a shot) and R1.6 (a grid at 0.7 m) pass or fail as asked; nothing else differs."""
    shot, grid = _params("radiosity", "R2.3"), _params("radiosity", "R1.6")
    return _package(root, "radiosity", RADIOSITY_ORACLE.format(
        shot=json.dumps({"i": shot["i"], "areas": shot["areas"]}),
        grid=json.dumps({"max_edge": grid["max_edge"], "quads": grid["quads"]}),
        pass_shot=pass_hidden_shot, pass_grid=pass_hidden_grid))


@pytest.mark.spawns
def test01_a_hidden_result_changes_nothing_a_student_sees_in_any_local_output():
    """R2.3 failing on purpose once added "R2 shoot() loses points in its own tests" to every visible R3 test and
    moved the top-level score 15 -> 12.5; the hidden grid case passing once gave visible edge case R1.3 its point."""
    top = world_readable_dir("cs451-oracle-")
    try:
        graded = []
        for shot, grid in ((True, False), (False, True)):    # one folder, so the reports name the same submission
            shutil.rmtree(top / "sub", ignore_errors=True)
            graded.append(grade("radiosity", radiosity_oracle(top / "sub", shot, grid), show_progress=False,
                                tasks=["R1", "R2", "R3"]))
        a, b = graded
        hidden = {r.test.number: (ra.score, r.score) for ra, r in zip(a.results, b.results) if r.test.hidden}
        assert hidden["R2.3"][0] > hidden["R2.3"][1] and hidden["R1.6"][0] < hidden["R1.6"][1], hidden
        assert total_score(to_gradescope(a)) != total_score(to_gradescope(b))     # the grade itself does differ
        assert seen_before_publication(to_gradescope(a)) == seen_before_publication(to_gradescope(b))
        assert render_report(a, show_hidden=False) == render_report(b, show_hidden=False)
        assert table_without_hidden_rows(format_table(a)) == table_without_hidden_rows(format_table(b))
        visible_r3 = [r.verdict.message for r in b.results if r.test.task == "R3" and not r.test.hidden]
        assert visible_r3 and all("relies on your own R2 shoot()" in m and "loses points" not in m for m in visible_r3)
        hidden_r3 = [r.verdict.message for r in b.results if r.test.task == "R3" and r.test.hidden]
        assert all("R2 shoot() loses points in its own tests" in m for m in hidden_r3), hidden_r3   # shown once published
        r13 = next(r for r in b.results if r.test.number == "R1.3")
        assert r13.score == 0 and "counts only once another R1 test passes" in r13.verdict.message
    finally:
        shutil.rmtree(top, ignore_errors=True)


SPHERE_ORACLE = '''

_right_perspective = perspective
_HIDDEN = {hidden}


def perspective(fovy, aspect, near, far):
    """Right, except on the hidden case's own arguments when told to fail it."""
    import numpy as np
    m = _right_perspective(fovy, aspect, near, far)
    return m * 0 if {fail} and [fovy, aspect, near, far] == _HIDDEN else m
'''


def sphere_oracle(root: Path, fail_hidden: bool) -> Path:
    p = _params("sphere", "S1.3")
    return _package(root, "sphere", SPHERE_ORACLE.format(
        hidden=[p["fovy"], p["aspect"], p["near"], p["far"]], fail=fail_hidden))


@pytest.mark.spawns
@pytest.mark.parametrize("mode", ["bubblewrap", "uid"])
def test02_on_gradescope_the_top_level_shows_nothing_of_a_hidden_result(gradescope, mode):
    """The zip's results.json once said 20 or 16 (S1 and S2) by whether hidden S1.3 passed; now it has no top-level
    score while hidden tests are in it, so Gradescope adds up the tests' scores (hidden ones once published)."""
    top = world_readable_dir("cs451-oracle-gs-")
    root, env = gradescope
    try:
        runs = [run_autograder((root, {**env, "CS451_SANDBOX": mode}), sphere_oracle(top / str(fail), fail), "--tasks", "S1,S2")
                for fail in (False, True)]
        points = sum(t.points for t in load_tests("sphere") if t.task in ("S1", "S2"))
        s13 = next(t.points for t in load_tests("sphere") if t.number == "S1.3")
        assert [total_score(r) for r in runs] == [pytest.approx(points), pytest.approx(points - s13)]
        assert all("score" not in r and "execution_time" not in r for r in runs)
        assert seen_before_publication(runs[0]) == seen_before_publication(runs[1])
    finally:
        shutil.rmtree(top, ignore_errors=True)


# --- item 6: control characters ------------------------------------------------------------------------

#: Clear the screen, retitle the terminal, reverse the text's direction, a C1 CSI, a carriage return.
HOSTILE = "\x1b[2J\x1b]0;owned\x07\u202e\x9b\r"
UNSAFE = {"Cc", "Cf", "Cs", "Zl", "Zp"}


def unsafe(text: str) -> list[str]:
    """The control, bidi and other invisible characters in ``text`` (newlines and tabs allowed; CSV's CRLF too)."""
    return sorted({c for c in text.replace("\r\n", "\n") if unicodedata.category(c) in UNSAFE and c not in "\n\t"})


def strings_in(data) -> str:
    """Every string of a decoded JSON document, joined: what a page shows once it has parsed the file."""
    if isinstance(data, dict):
        return "\n".join(strings_in(k) + "\n" + strings_in(v) for k, v in data.items())
    if isinstance(data, list):
        return "\n".join(strings_in(v) for v in data)
    return data if isinstance(data, str) else ""


def escapes_everywhere(root: Path, name: str) -> Path:
    """S1 prints and raises text full of escape sequences, the interface answer names a problem made of them, and
    the upload holds a link whose name carries them (the copy leaves it out and says so)."""
    forged = ("import json as _j, os as _o\n"
              "if _j.load(open('request.json'))['probe'] == '__interface__':\n"
              f"    np.savez('output.npz', problems=np.array(['PROBLEM' + {HOSTILE!r}]))\n"
              "    open('status.json', 'w').write('{\"ok\": true}')\n    _o._exit(0)\n")
    code = f"    print('PRINTED' + {HOSTILE!r})\n    raise ValueError('RAISED' + {HOSTILE!r})\n"
    folder = attack(root, name, code, at_import=forged)
    (folder / "sphere" / f"link{HOSTILE}").symlink_to("/etc/hostname")
    return folder


def assert_printable(where: str, text: str, *markers: str) -> None:
    assert not unsafe(text), f"{where}: {[hex(ord(c)) for c in unsafe(text)]}"
    for marker in markers:   # the text is still there, escaped: nothing a student wrote is silently lost
        assert f"{marker}\\x1b[2J\\x1b]0;owned\\x07\\u202e\\x9b" in text, f"{where}: {marker} not shown escaped"


@pytest.mark.spawns
def test03_escape_sequences_reach_no_terminal_file_or_page_of_the_kit(tmp_path):
    """`cs451 grade` from this kit: its table on the terminal, its results.json and its report."""
    top = world_readable_dir("cs451-escapes-")
    try:
        sub = escapes_everywhere(top, "sub")
        done = subprocess.run([sys.executable, "-m", "cs451", "grade", "sphere", "--submission", str(sub), "--tasks",
                               "S1,S2", "--results", str(tmp_path / "results.json"), "--report", str(tmp_path / "report"),
                               "--fail-under", "0"],   # graded, whatever the grade: exit 0
                              cwd=KIT_ROOT, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr[-2000:]
        assert_printable("terminal", done.stdout + done.stderr, "RAISED", "PROBLEM", "link")
        data = json.loads((tmp_path / "results.json").read_text())
        assert_printable("results.json", strings_in(data), "RAISED", "PRINTED", "PROBLEM", "link")
        assert_printable("report.html", (tmp_path / "report" / "report.html").read_text(), "RAISED", "PRINTED", "PROBLEM")
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.mark.spawns
def test04_escape_sequences_reach_no_gradebook_and_no_report_of_a_roster(tmp_path):
    """A roster whose student folder's own name carries them too."""
    top = world_readable_dir("cs451-escapes-")
    try:
        escapes_everywhere(top / "class", f"mallory{HOSTILE}")
        grade_roster(stage="sphere", roster=top / "class", output=tmp_path / "grades", show_progress=False, only=["S1", "S2"])
        book = (tmp_path / "grades" / "gradebook.csv").read_text()
        assert_printable("gradebook.csv", book, "mallory", "PROBLEM")
        row = next(csv.DictReader(io.StringIO(book)))
        assert float(row["score"]) == 10 and float(row["S2"]) == 10, row   # S1 raised; S2 is the control
        student = tmp_path / "grades" / f"mallory{HOSTILE}"
        assert_printable("results.json", strings_in(json.loads((student / "results.json").read_text())), "RAISED", "PRINTED")
        assert_printable("report.html", (student / "report.html").read_text(), "RAISED", "PRINTED", "PROBLEM")
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.mark.spawns
@pytest.mark.parametrize("mode", ["bubblewrap", pytest.param("uid", marks=pytest.mark.slow)])
def test05_escape_sequences_reach_no_gradescope_results(gradescope, mode):
    """The zip's run_autograder, in the layout its own setup.sh makes."""
    top = world_readable_dir("cs451-escapes-")
    root, env = gradescope
    try:
        data = run_autograder((root, {**env, "CS451_SANDBOX": mode}), escapes_everywhere(top, "sub"), "--tasks", "S1,S2")
        assert_printable("results.json", strings_in(data), "RAISED", "PRINTED", "PROBLEM", "link")
        assert total_score(data) == 10
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.mark.spawns
def test06_escape_sequences_reach_no_classroom_step_output():
    """The student release's workflow, its grading and per-task commands run as written (the kit's Python in place
    of the release's set-up .venv): what each step prints, and the results and report it keeps."""
    top = world_readable_dir("cs451-escapes-")
    try:
        release = build_release("sphere", top / "repo")
        shutil.rmtree(release / "sphere")
        shutil.copytree(escapes_everywhere(top, "sub") / "sphere", release / "sphere", symlinks=True)
        for path in [top, *top.rglob("*")]:
            if not path.is_symlink():
                path.chmod(0o755 if path.is_dir() else 0o644)
        commands = re.findall(r"^\s+(?:run|command): (.+)$", (release / ".github" / "workflows" / "classroom.yml").read_text(),
                              flags=re.M)
        assert commands[0] == "./setup.sh" and all(c.startswith(".venv/bin/cs451 ") for c in commands[1:])
        printed = []
        for command in commands[1:]:
            args = [sys.executable, "-m", "cs451", *command.split()[1:]]
            done = subprocess.run(args, cwd=release, capture_output=True, text=True, timeout=600,
                                  env={"PATH": os.environ["PATH"], "HOME": str(top)})
            printed.append(done.stdout + done.stderr)
            assert done.returncode in (0, 1), done.stderr[-2000:]
        assert_printable("the workflow's steps", "\n".join(printed), "RAISED", "PROBLEM", "link")
        assert_printable("results.json", strings_in(json.loads((release / "results.json").read_text())), "RAISED", "PRINTED")
        assert_printable("report.html", (release / "report" / "report.html").read_text(), "RAISED", "PRINTED", "PROBLEM")
    finally:
        shutil.rmtree(top, ignore_errors=True)


def test07_printable_escapes_what_a_terminal_obeys_or_hides_and_keeps_the_rest():
    """The one function every output goes through: invisible and steering characters become their escapes;
    the kit's own symbols and any language's letters stay as they are."""
    from cs451.grading.untrusted import printable
    kept = "ꟻLIP × ≤ ─ ✓ é 日本 مرحبا"
    assert printable(kept) == kept and printable("a\tb\nc") == "a\tb\nc"
    assert printable("a\tb\nc", lines=False) == "a\\tb\\nc"
    assert printable("\x1b[31m\x07\x7f\x9b\r") == "\\x1b[31m\\x07\\x7f\\x9b\\x0d"
    assert printable("\u202e\u2066\u200b\ufeff\u2028") == "\\u202e\\u2066\\u200b\\ufeff\\u2028"
    assert printable("\ud800\U000e0041") == "\\ud800\\U000e0041"    # a lone surrogate; an invisible tag letter
    assert not unsafe(printable("".join(map(chr, range(0x2100)))))


# --- item 8: memory before refusal ----------------------------------------------------------------------

def huge_answer(stored_mib: int, deflated_mib: int) -> str:
    """Code run when the package is imported for any test (the interface check aside): leave an answer of two float
    arrays, one stored and one deflated (zeros: a few KiB on disk), of these sizes, and report success."""
    return ("import io as _io, json as _json, os as _os, zipfile as _zipfile\n"
            "def _member(z, name, mib, method):\n"
            "    head = _io.BytesIO()\n"
            "    np.lib.format.write_array_header_1_0(head, {'descr': '<f8', 'fortran_order': False, 'shape': (mib << 17,)})\n"
            "    info = _zipfile.ZipInfo(name + '.npy')\n"
            "    info.compress_type = method\n"
            "    with z.open(info, 'w', force_zip64=True) as f:\n"
            "        f.write(head.getvalue())\n"
            "        for _ in range(mib):\n"
            "            f.write(bytes(1 << 20))\n"
            "if _json.load(open('request.json'))['probe'] != '__interface__':\n"
            "    with _zipfile.ZipFile('output.npz', 'w') as z:\n"
            f"        _member(z, 'a', {stored_mib}, _zipfile.ZIP_STORED)\n"
            f"        _member(z, 'b', {deflated_mib}, _zipfile.ZIP_DEFLATED)\n"
            "    open('status.json', 'w').write('{\"ok\": true, \"error\": \"\"}')\n    _os._exit(0)\n")


#: Over the limit (256 MiB, all the old reader allowed) and just under it (79 MiB of untrusted.ARRAYS_LIMIT's 80).
HUGE = {"over": (120, 136), "under": (40, 39)}

MEASURED_GRADE = """
import json, resource, sys
from cs451.grading.runner import grade
result = grade("sphere", sys.argv[1], show_progress=False, tasks=["S1", "S2"], test_timeout=60, jobs=2)
print(json.dumps({"peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "points": {t: sum(r.score for r in result.results if r.test.task == t) for t in ("S1", "S2")},
                  "messages": [r.verdict.message for r in result.results]}))
"""


def graded_with_peak(folder: Path) -> dict:
    """Grade S1 and S2 locally, two tests at once, in a fresh process: its points, messages and peak RSS."""
    done = subprocess.run([sys.executable, "-c", MEASURED_GRADE, str(folder)], cwd=KIT_ROOT, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.spawns
def test08_a_huge_answer_costs_the_grader_no_more_than_the_limit_two_tests_at_once():
    """Every test's answer huge. The old reader took the whole file, then each array's bytes and a copy, and the
    grader kept every answer until the end. Now an answer over the limit is refused from its headers, unread, and
    one under it is held once, by at most two tests at a time (one per worker)."""
    from cs451.grading.untrusted import ARRAYS_LIMIT
    top = world_readable_dir("cs451-huge-")
    try:
        honest = graded_with_peak(attack(top, "honest"))
        assert honest["points"] == {"S1": 10, "S2": 10}
        for name, (stored, deflated) in HUGE.items():
            out = graded_with_peak(attack(top, name, at_import=huge_answer(stored, deflated)))
            assert out["points"] == {"S1": 0, "S2": 0}, out
            extra = out["peak_mib"] - honest["peak_mib"]
            if name == "over":
                assert all("would take" in m and "80 MiB for the whole answer" in m for m in out["messages"]), out
                assert extra < 16, out
            else:
                assert not [m for m in out["messages"] if "could not be read" in m], out
                assert extra < 2 * (ARRAYS_LIMIT >> 20) + 16, out
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.mark.spawns
def test09_on_gradescope_a_huge_answer_stays_well_inside_its_768_mb(gradescope):
    """The zip's run_autograder, one test at a time as on Gradescope: the whole process tree (grader, sandbox and
    worker), sampled, stays well under Gradescope's default 768 MB with every answer just under the limit."""
    from bench.autograder import _run_measured
    root, env = gradescope
    top = world_readable_dir("cs451-huge-gs-")
    try:
        for sub in ("submission", "results"):
            shutil.rmtree(root / sub, ignore_errors=True)
            (root / sub).mkdir()
        folder = attack(top, "under", at_import=huge_answer(*HUGE["under"]))
        subprocess.run(["cp", "-a", f"{folder}/.", str(root / "submission")], check=True)
        seconds, peak_mb, code = _run_measured([str(root / "source" / "run_autograder"), "--tasks", "S1,S2"],
                                               {**env, "CS451_SANDBOX": "bubblewrap"})
        results = json.loads((root / "results" / "results.json").read_text())
        assert code == 0 and total_score(results) == 0 and len(results["tests"]) > 0, results.get("output")
        assert peak_mb < 0.6 * 768, f"{peak_mb:.0f} MB at the peak in {seconds:.1f} s"
    finally:
        shutil.rmtree(top, ignore_errors=True)


def test10_the_reader_returns_what_numpy_wrote_and_refuses_a_huge_directory_before_parsing_it(tmp_path):
    """In place and chunked, the reader still returns every array np.savez writes, stored or deflated; a zip
    directory of 100,000 entries (zipfile parses it whole: 56 MiB for this 9 MiB file) is refused from its end record,
    even when that record claims one entry."""
    import zipfile
    import numpy as np
    from cs451.grading.untrusted import UntrustedError, read_arrays
    arrays = {"x": np.arange(12.0).reshape(3, 4), "f": np.asfortranarray(np.arange(6).reshape(2, 3)),
              "t": np.array(["ab", "cde"]), "b": np.array([True, False]), "e": np.zeros((0, 3)), "s": np.float32(2.5),
              "big_endian": np.arange(10, dtype=">i4")}
    for save in (np.savez, np.savez_compressed):
        save(tmp_path / "answer.npz", **arrays)
        got = read_arrays(tmp_path / "answer.npz")
        assert set(got) == set(arrays)
        for k, want in arrays.items():
            assert got[k].dtype == np.asarray(want).dtype and np.array_equal(got[k], want), k
        assert got["f"].flags.f_contiguous and got["x"].flags.writeable
    with zipfile.ZipFile(tmp_path / "many.npz", "w") as z:
        for i in range(100_000):
            z.writestr(f"a{i}.npy", b"")
    with pytest.raises(UntrustedError, match="directory is larger than 64 arrays need"):
        read_arrays(tmp_path / "many.npz")
    data = bytearray((tmp_path / "many.npz").read_bytes())
    end = data.rfind(b"PK\x05\x06")
    data[end + 8:end + 12] = (1).to_bytes(2, "little") * 2      # the end record claims one entry
    (tmp_path / "lying.npz").write_bytes(bytes(data))
    with pytest.raises(UntrustedError, match="directory is larger than 64 arrays need"):
        read_arrays(tmp_path / "lying.npz")
