#!/usr/bin/env python3
"""Lists the functions in C++ sources longer than N lines (default 100; docs/architecture.md:
"no function longer than a screen"), longest first per file.

  /usr/bin/python3 scripts/long_functions.py [N] [DIR ...]      (default: src)

A heuristic brace counter, not a parser: a '{' whose text before it (on its line, or the line
above) ends like a function signature -- ')' [const] [noexcept] [override] [-> T] -- opens a
function; a class or struct body is not counted itself, but its member functions are. Lambdas and
blocks inside a function count towards that function. Exits 1 when it lists any, so a script or a
reviewer can use it as a check."""
import pathlib
import re
import sys

SIGNATURE = re.compile(r"\)\s*(const)?\s*(noexcept)?\s*(override)?\s*(->\s*[\w:<>,\s&*]+)?\s*$")
CONTROL = re.compile(r"(if|for|while|switch|catch)\b")
CLASS = re.compile(r"(class|struct)\s+\w+")


def code_of(line):
    """The line without string and character literals (their braces are not code)."""
    line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
    return re.sub(r"'(\\.|[^'\\])*'", "''", line)


def long_functions(path, limit):
    lines = path.read_text(errors="replace").split("\n")
    stack = []  # (first line, kind, text): kind is "function", "class" or None
    in_comment = False
    for i, raw in enumerate(lines):
        line = raw
        if in_comment:
            if "*/" not in line:
                continue
            line, in_comment = line.split("*/", 1)[1], False
        line = code_of(line.split("//")[0])
        if "/*" in line:
            in_comment = "*/" not in line
            line = line.split("/*")[0]
        for j, ch in enumerate(line):
            if ch == "{":
                head = line[:j].strip() or (lines[i - 1].strip() if i else "")
                kind = None
                if CLASS.match(head) and not head.endswith(";"):
                    kind = "class"
                elif SIGNATURE.search(head) and not CONTROL.match(head.lstrip("} ")):
                    kind = "function"
                stack.append((i, kind, head))
            elif ch == "}" and stack:
                start, kind, head = stack.pop()
                outer = [k for _, k, _ in stack if k]
                if kind == "function" and (not outer or outer[-1] == "class") and i - start + 1 > limit:
                    yield i - start + 1, start + 1, head


def main():
    args = sys.argv[1:]
    limit = int(args.pop(0)) if args and args[0].isdigit() else 100
    found = 0
    for root in args or ["src"]:
        for path in sorted(pathlib.Path(root).rglob("*.[ch]pp")):
            for length, line, head in sorted(long_functions(path, limit), reverse=True):
                print(f"{length:5d} {path}:{line}: {head[:90]}")
                found += 1
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
