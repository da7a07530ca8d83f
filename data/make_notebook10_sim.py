"""Make data/notebook10_sim.json: notebook 10's circuit through make csim (g++) and make rtlsim
(Icarus Verilog), for machines without those tools (the notebook shows this file then).

Run from the repository root with the lab installed and g++, make and iverilog on PATH:

    python data/make_notebook10_sim.py

The message and the configuration are the notebook's example (``EXAMPLE_MSG_TEXT`` and
``EXAMPLE_CONFIG_TEXT`` in notebooks/solutions/10_your_own_message.ipynb, read here, one owner;
returned as ``MSG_TEXT`` and ``CONFIG_TEXT``, the texts the notebook runs unless a student
changes them); the project is what
``rosfpga-lab generate`` writes for them and the frames are its testbench's (``tb_input.bin``:
a good frame, a refused one, a good one). tests/flow/test_notebook10_shipped.py checks that the file
belongs to the notebook's texts and, with the tools, makes it again and compares.
"""

from __future__ import annotations

import ast
import hashlib
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOK = ROOT / "notebooks" / "solutions" / "10_your_own_message.ipynb"
OUT = Path(__file__).resolve().parent / "notebook10_sim.json"
#: Where the notebook writes its message (``msg/<package>/msg/<Name>.msg`` under its folder).
MSG_FILE = "msg/my_msgs/msg/LineScan.msg"
#: The RTL simulation's input gaps and output backpressure (per mille) and seed.
GAP, BP, SEED = 300, 300, 1


#: The notebook's variables read here, and the keys they are returned under.
NAMES = {"EXAMPLE_MSG_TEXT": "MSG_TEXT", "EXAMPLE_CONFIG_TEXT": "CONFIG_TEXT"}


def notebook_texts(path: Path = NOTEBOOK) -> dict[str, str]:
    """``MSG_TEXT`` and ``CONFIG_TEXT``: the example's texts as the notebook's cells assign
    them (``EXAMPLE_MSG_TEXT``, ``EXAMPLE_CONFIG_TEXT``)."""
    found: dict[str, str] = {}
    for cell in json.loads(path.read_text(encoding="utf-8"))["cells"]:
        if cell["cell_type"] != "code":
            continue
        source = "".join(cell["source"])
        try:
            tree = ast.parse(source)
        except SyntaxError:
            continue
        for node in tree.body:
            if (isinstance(node, ast.Assign) and len(node.targets) == 1
                    and isinstance(node.targets[0], ast.Name)
                    and node.targets[0].id in NAMES
                    and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)):
                found[NAMES[node.targets[0].id]] = node.value.value
    missing = {name for name, key in NAMES.items() if key not in found}
    if missing:
        raise SystemExit(f"{path}: no cell assigns {', '.join(sorted(missing))} a string")
    return found


def sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def make_result(texts: dict[str, str]) -> dict[str, Any]:
    """Generate the project of ``texts`` in a temporary folder and simulate it both ways."""
    from rosfpga_lab.config import parse_config
    from rosfpga_lab.rtl.generic import simulate_project
    from rosfpga_lab.rtl.project import generate_project

    with tempfile.TemporaryDirectory(prefix="rosfpga-nb10-") as tmp:
        root = Path(tmp)
        (root / MSG_FILE).parent.mkdir(parents=True)
        (root / MSG_FILE).write_text(texts["MSG_TEXT"], encoding="utf-8")
        config = parse_config(texts["CONFIG_TEXT"], source="notebook 10", base_dir=root)
        project = root / "project"
        generate_project(config, project)
        frames = (project / "tb_input.bin").read_bytes()
        expected = (project / "tb_expected.bin").read_bytes()
        c_out, c_status = simulate_project(project, frames, target="csim")
        r_out, r_status = simulate_project(project, frames, target="rtlsim", simulator="iverilog",
                                           gap=GAP, bp=BP, seed=SEED)
    return {
        "made_by": "data/make_notebook10_sim.py",
        "msg_text": texts["MSG_TEXT"], "config_text": texts["CONFIG_TEXT"],
        "input_sha256": sha(frames), "expected_sha256": sha(expected),
        "csim": {"statuses": c_status, "output_sha256": sha(c_out), "output_bytes": len(c_out)},
        "rtlsim": {"simulator": "iverilog", "gap": GAP, "bp": BP, "seed": SEED,
                   "statuses": r_status, "output_sha256": sha(r_out),
                   "output_bytes": len(r_out)},
    }


def main() -> int:
    result = make_result(notebook_texts())
    OUT.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    same = result["csim"]["output_sha256"] == result["rtlsim"]["output_sha256"] \
        == result["expected_sha256"]
    print(f"{OUT}: csim {result['csim']['statuses']}, rtlsim {result['rtlsim']['statuses']}, "
          f"both equal the models' output: {same}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
