#!/usr/bin/python3
"""The docs test must fail, naming the document, line, command and stderr, when a documented command
fails; and must refuse the conventions' misuses. Runs run_doc_commands.py on a small made-up source
tree (tests/docs/run_doc_commands.py; docs/reliability.md, "Docs that are tested").

Usage: run_doc_commands_selftest.py --errfield BIN
"""
import argparse
import os
import subprocess
import sys
import tempfile

DOC = """# made up

```sh
errfield simulate --sample cells --out t.csv
errfield fk --input t.csv --robot no_such_robot.json --out p.csv
```

<!-- not-run: needs a robot controller -->
```sh
errfield fk --input from_the_controller.csv --out p.csv
```

<!-- not-run: -->
```sh
errfield robots
```

```sh
errfield robots   # not-run: slow: an example of a slow one
```

```xml file=made.txt
hello
```

```sh
grep -q hello made.txt
```

    errfield robots --show kr16

```
errfield robots --show ur5e
```
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--errfield", required=True)
    a = ap.parse_args()
    here = os.path.dirname(os.path.abspath(__file__))
    with tempfile.TemporaryDirectory(prefix="errfield-docs-selftest-") as src:
        os.makedirs(os.path.join(src, "docs"))
        os.makedirs(os.path.join(src, "scripts"))
        os.makedirs(os.path.join(src, "data"))
        open(os.path.join(src, "README.md"), "w").write("# nothing to run\n")
        open(os.path.join(src, "docs", "made_up.md"), "w").write(DOC)
        p = subprocess.run([sys.executable, os.path.join(here, "run_doc_commands.py"), "--errfield", a.errfield,
                            "--source", src, "--only", "docs/made_up.md"], capture_output=True, text=True)
        out = p.stdout + p.stderr
    lines = DOC.split("\n")
    line_of = lambda text: next(i + 1 for i, l in enumerate(lines) if text in l)
    expected = [
        # the failing command, by document and line, with errfield's own message
        f"FAILED docs/made_up.md:{line_of('no_such_robot')}: exit 2: errfield fk --input t.csv --robot no_such_robot.json",
        "no_such_robot.json",
        # not run, with the reason; slow ones are skipped without --include-slow
        f"skipped docs/made_up.md:{line_of('from_the_controller')}: errfield fk --input from_the_controller.csv --out p.csv "
        "-- needs a robot controller",
        "-- slow: an example of a slow one",
        # a reason is required
        f"PROBLEM docs/made_up.md:{line_of('<!-- not-run: -->') + 1}: '<!-- not-run: -->' without a reason",
        # commands outside sh/text blocks are refused
        f"PROBLEM docs/made_up.md:{line_of('--show kr16')}: an errfield command in an indented code block",
        f"PROBLEM docs/made_up.md:{line_of('--show ur5e')}: an errfield command in a ``` block",
    ]
    missing = [e for e in expected if e not in out]
    # Ran: simulate, fk (fails) and grep (the file= block is written first, so it succeeds); skipped:
    # the controller block, the block without a reason (also a problem) and the slow command.
    if p.returncode != 1:
        missing.append(f"exit status 1 (got {p.returncode})")
    if "FAILED docs/made_up.md:" + str(line_of("grep -q hello")) in out:
        missing.append("the file= block written before the command that reads it")
    if "ran 3 commands, skipped 3" not in out:
        missing.append("'ran 3 commands, skipped 3'")
    if missing:
        print("run_doc_commands.py did not report:\n  " + "\n  ".join(missing) + "\nIts output:\n" + out)
        return 1
    print("run_doc_commands.py reports failures, skips and convention problems as documented")
    return 0


if __name__ == "__main__":
    sys.exit(main())
