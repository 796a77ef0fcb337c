#!/usr/bin/python3
"""Runs the errfield commands of README.md, docs/*.md and every subcommand's --help examples as written.

The convention (docs/reliability.md, "Docs that are tested"):
- In README.md and docs/*.md, every fenced code block whose info string is `sh` is run: each command
  (a line, joined with the next while it ends in a backslash; blank and `#` comment lines skipped)
  runs with `bash -c` (as typed: no pipefail, so `grep | head` is fine) in one temporary directory
  per document, in the document's order, so an earlier command makes the files a later one reads.
  OMP_NUM_THREADS is 1 unless set. `errfield` is the built binary (first on PATH, and
  `build/errfield`); `scripts/` and `data/` are the source tree's (symlinks), so commands written
  from the repository root work as written. A line `NAME=value` (a shell variable) is
  prepended to the document's later commands.
- A block is not run only when the line just before its fence is `<!-- not-run: REASON -->`; one
  command is not run only when it ends in `# not-run: REASON`. REASON must not be empty. A REASON
  starting with `slow` (a measured figure's full reproduction, seconds of CPU each) is run with
  --include-slow; anything else (installs packages, needs hardware or another build) never.
- A fenced block whose info string holds `file=NAME` (e.g. ```xml file=demo.urdf) is written to NAME
  in the document's directory at that point, for the commands after it to read.
- Command synopses (`[--option]`, `A|B`) go in ```text blocks. An `errfield` command in an indented
  code block, or in a fenced block of any other kind, fails the check: mark it `sh` or `text`.
- --help examples: `errfield --help` lists the commands; in `errfield CMD --help`, a line
  `Example: errfield ...` or a line starting with `  errfield ` after a line `Example...:` is a
  command (continued by a trailing backslash; `  # ...` after it is a remark). They all run in one
  directory, after the README block marked `<!-- help-examples-inputs -->`, which makes their inputs.
A failure names the document, line and command, its exit status and its standard error. At the end
the script prints how many commands it ran and skipped (with the reasons) and the time taken.

Usage: run_doc_commands.py --errfield BIN --source DIR [--only NAME] [--include-slow] [--keep]
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

NOT_RUN_BLOCK = re.compile(r"^<!--\s*not-run:(.*)-->\s*$")
NOT_RUN_LINE = re.compile(r"\s#\s*not-run:(.*)$")
HELP_INPUTS_MARK = "<!-- help-examples-inputs -->"
ASSIGNMENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*=\S")
COMMAND_TIMEOUT_S = 120


class Command:
    def __init__(self, doc, line, text, skip_reason=None, file_name=None):
        self.doc, self.line, self.text, self.skip_reason = doc, line, text, skip_reason
        self.file_name = file_name  # a file= block: write text to this file instead of running it


class DocProblem(Exception):
    pass


def join_continuations(lines):
    """(first line number, logical line) for the lines of a block, joining backslash continuations."""
    out, current, start = [], None, 0
    for number, raw in lines:
        line = raw.rstrip()
        if current is None:
            current, start = line, number
        else:
            current += "\n" + line
        if line.endswith("\\"):
            continue
        out.append((start, current))
        current = None
    if current is not None:
        out.append((start, current))
    return out


def commands_of_block(doc, lines, block_reason):
    commands = []
    for number, text in join_continuations(lines):
        stripped = text.strip()
        if not stripped or stripped.startswith("#"):
            continue
        reason = block_reason
        m = NOT_RUN_LINE.search(text)
        if m:
            reason = m.group(1).strip()
            if not reason:
                raise DocProblem(f"{doc}:{number}: '# not-run:' without a reason")
            text = text[: m.start()].rstrip()
        commands.append(Command(doc, number, text, reason))
    return commands


def parse_markdown(path, doc):
    """Commands of the sh blocks of one document, in order, and the help-inputs block's commands."""
    lines = open(path, encoding="utf-8").read().split("\n")
    commands, help_inputs, problems = [], [], []
    i = 0
    previous_nonblank = ""
    while i < len(lines):
        line = lines[i]
        fence = re.match(r"^(\s*)(```+|~~~+)\s*([^\s`]*)(.*)$", line)
        if fence:
            marker, info = fence.group(2), fence.group(3)
            file_name = re.search(r"\bfile=(\S+)", fence.group(4))
            start = i + 1
            j = start
            while j < len(lines) and not lines[j].strip().startswith(marker):
                j += 1
            body = [(k + 1, lines[k]) for k in range(start, j)]
            before = previous_nonblank.strip()
            if info == "sh":
                reason = None
                m = NOT_RUN_BLOCK.match(before)
                if m:
                    reason = m.group(1).strip()
                    if not reason:
                        problems.append(f"{doc}:{i + 1}: '<!-- not-run: -->' without a reason")
                try:
                    block = commands_of_block(doc, body, reason)
                except DocProblem as e:
                    problems.append(str(e))
                    block = []
                commands += block
                if before == HELP_INPUTS_MARK:
                    help_inputs = block
            elif file_name:
                if "/" in file_name.group(1) or file_name.group(1).startswith("."):
                    problems.append(f"{doc}:{i + 1}: file={file_name.group(1)}: a plain file name, please")
                else:
                    commands.append(Command(doc, i + 1, "\n".join(t for _, t in body) + "\n", None, file_name.group(1)))
            elif info != "text":
                for number, text in body:
                    if text.strip().startswith("errfield "):
                        problems.append(f"{doc}:{number}: an errfield command in a ```{info} block: "
                                        "fence it as ```sh (run by this test) or ```text (a synopsis)")
            previous_nonblank = ""
            i = j + 1
            continue
        if re.match(r"^ {4,}errfield ", line):
            problems.append(f"{doc}:{i + 1}: an errfield command in an indented code block: "
                            "fence it as ```sh (run by this test) or ```text (a synopsis)")
        if line.strip():
            previous_nonblank = line
        i += 1
    return commands, help_inputs, problems


def help_commands(errfield, env):
    """(command name, [Command]) for every subcommand's --help examples."""
    top = subprocess.run([errfield, "--help"], capture_output=True, text=True, env=env).stdout
    names = []
    in_list = False
    for line in top.split("\n"):
        if line.startswith("Subcommands:"):
            in_list = True
            continue
        if in_list:
            m = re.match(r"^  (\S+)(\s|$)", line)
            if m:
                names.append(m.group(1))
            elif not line.startswith("   ") and line.strip():
                in_list = False
    if not names:
        raise DocProblem("could not read the command list from 'errfield --help':\n" + top)
    result = []
    for name in names:
        text = subprocess.run([errfield, name, "--help"], capture_output=True, text=True, env=env).stdout
        doc = f"errfield {name} --help"
        lines = text.split("\n")
        picked = []
        in_examples = False
        k = 0
        while k < len(lines):
            line = lines[k]
            m = re.match(r"^\s*Example\b.*?:\s*(errfield .*)?$", line)
            start = None
            if m:
                in_examples = True
                if m.group(1):
                    start = m.group(1)
            elif in_examples and re.match(r"^ {2,}errfield ", line):
                start = line.strip()
            elif in_examples and not line.startswith(" "):
                in_examples = False
            if start is not None:
                number = k + 1
                body = [(number, start)]
                while body[-1][1].rstrip().endswith("\\") and k + 1 < len(lines):
                    k += 1
                    body.append((k + 1, lines[k]))
                picked += body
            k += 1
        cmds = []
        for number, cmd in join_continuations(picked):
            # A remark after the command: two or more spaces then '#'.
            cmd = re.sub(r"\s{2,}#(?!\s*not-run:).*$", "", cmd)
            cmds += commands_of_block(doc, [(number, cmd)], None)
        result.append((name, cmds))
    return result


def prepare_directory(root, name, source, errfield):
    d = os.path.join(root, re.sub(r"[^A-Za-z0-9_.-]", "_", name))
    os.makedirs(os.path.join(d, "build"))
    for sub in ("scripts", "data"):
        os.symlink(os.path.join(source, sub), os.path.join(d, sub))
    os.symlink(errfield, os.path.join(d, "build", "errfield"))
    return d


def run_commands(commands, directory, env, ran, skipped, failures, timing, include_slow=False):
    prelude = []
    for c in commands:
        if c.skip_reason is not None and not (include_slow and c.skip_reason.startswith("slow")):
            skipped.append(c)
            continue
        if c.file_name:
            with open(os.path.join(directory, c.file_name), "w", encoding="utf-8") as f:
                f.write(c.text)
            continue
        if ASSIGNMENT.match(c.text):
            prelude.append(c.text)
            script = "\n".join(prelude)
        else:
            script = "\n".join(prelude + [c.text])
        t0 = time.monotonic()
        try:
            p = subprocess.run(["bash", "-c", script], cwd=directory, env=env,
                               capture_output=True, text=True, timeout=COMMAND_TIMEOUT_S)
            status, err = p.returncode, p.stderr
        except subprocess.TimeoutExpired as e:
            status, err = "timeout", f"still running after {COMMAND_TIMEOUT_S} s\n" + (e.stderr or b"").decode(errors="replace")
        elapsed = time.monotonic() - t0
        timing.append((elapsed, c))
        ran.append(c)
        if status != 0:
            tail = "\n".join(err.rstrip().split("\n")[-15:])
            failures.append(f"{c.doc}:{c.line}: exit {status}: {c.text}\n    stderr:\n      " +
                            tail.replace("\n", "\n      "))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--errfield", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--only", help="run one document only (e.g. README.md, docs/idw.md or help)")
    ap.add_argument("--keep", action="store_true", help="keep the temporary directory")
    ap.add_argument("--include-slow", action="store_true", help="also run what is marked 'not-run: slow...'")
    a = ap.parse_args()
    errfield = os.path.abspath(a.errfield)
    source = os.path.abspath(a.source)
    t_start = time.monotonic()
    root = tempfile.mkdtemp(prefix="errfield-docs-")
    bindir = os.path.join(root, "bin")
    os.makedirs(bindir)
    os.symlink(errfield, os.path.join(bindir, "errfield"))
    env = dict(os.environ)
    env["PATH"] = bindir + os.pathsep + env.get("PATH", "")
    env.pop("PYTHONPATH", None)
    # One OpenMP thread unless asked otherwise: ctest runs other tests beside this one, and the
    # fits' OpenMP loops slowed down 2-4x when oversubscribed (measured: 17 s vs 8 s on the loaded
    # 2-core machine). Outputs do not depend on it (docs/reliability.md, "Determinism").
    env.setdefault("OMP_NUM_THREADS", "1")

    docs = ["README.md"] + sorted("docs/" + f for f in os.listdir(os.path.join(source, "docs")) if f.endswith(".md"))
    ran, skipped, failures, problems, timing = [], [], [], [], []
    help_inputs = []
    for doc in docs:
        commands, inputs, doc_problems = parse_markdown(os.path.join(source, doc), doc)
        problems += doc_problems
        if doc == "README.md":
            help_inputs = inputs
        if a.only and a.only != doc:
            continue
        if commands:
            run_commands(commands, prepare_directory(root, doc, source, errfield), env, ran, skipped, failures, timing,
                         a.include_slow)
    if not help_inputs:
        problems.append(f"README.md: no ```sh block after '{HELP_INPUTS_MARK}' (the --help examples' inputs)")
    if not a.only or a.only == "help":
        try:
            helps = help_commands(errfield, env)
        except DocProblem as e:
            problems.append(str(e))
            helps = []
        for name, cmds in helps:
            if not cmds:
                problems.append(f"errfield {name} --help: no example")
        directory = prepare_directory(root, "help", source, errfield)
        inputs = [Command("README.md (help-examples inputs)", c.line, c.text, c.skip_reason) for c in help_inputs]
        run_commands(inputs + [c for _, cmds in helps for c in cmds], directory, env, ran, skipped, failures, timing)

    print(f"ran {len(ran)} commands, skipped {len(skipped)}, in {time.monotonic() - t_start:.1f} s wall")
    for c in skipped:
        print(f"  skipped {c.doc}:{c.line}: {c.text.splitlines()[0]} -- {c.skip_reason}")
    print("slowest:")
    for elapsed, c in sorted(timing, key=lambda x: -x[0])[:5]:
        print(f"  {elapsed:6.2f} s  {c.doc}:{c.line}: {c.text.splitlines()[0][:100]}")
    for p in problems:
        print("PROBLEM " + p)
    for f in failures:
        print("FAILED " + f)
    if a.keep:
        print("kept " + root)
    else:
        shutil.rmtree(root, ignore_errors=True)
    if problems or failures:
        print(f"{len(problems)} convention problem(s), {len(failures)} failed command(s)")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
