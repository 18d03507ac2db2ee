#!/usr/bin/env python3
"""Checks house rules on the code (docs/architecture.md, ../shared/STYLE.md).

  code_check.py functions ROOT  no function in src/, apps/ and ros/ is longer than 60 lines
                                (signature to closing brace; lambdas count in their function)
  code_check.py history ROOT    no comment in src/, apps/ and ros/ names a commit (7-40 hex digits
                                with a letter), a date it was true before ("before 2026-11-28"), a
                                figure's change ("14 -> 12 ms") or a measurement ("(measured: ...)"):
                                history and figures belong in commit messages and docs/

  code_check.py files ROOT      no file in src/ is longer than 600 lines
  code_check.py format ROOT     every C++ file of src/, apps/, ros/, tests/, bench/ and docs/examples/
                                is as clang-format writes it with the repository's .clang-format

Prints one line per problem and exits 1 if there is any.
"""
import glob
import os
import re
import shutil
import subprocess
import sys

MAX_LINES = 60
MAX_FILE_LINES = 600
FORMATTED = ("src", "apps", "ros", "tests", "bench", "docs/examples")
HISTORY = [
    (re.compile(r"\b(before|until|since|after)\s+\d{4}-\d{2}-\d{2}", re.I), "dates what was true before"),
    (re.compile(r"\d(\.\d+)?\s*(%|x|ms|s|m|px)?\s*(->|→)\s*\d+(\.\d+)?([–-]\d+(\.\d+)?)?\s*(%|x|ms|s|m|px)\b"),
     "narrates a figure's change"),
    (re.compile(r"\(measured:", re.I), "carries a measurement"),
]
CONTROL = re.compile(r"^\s*(\}?\s*else|if|for|while|switch|do|try|\}?\s*catch|return|case|namespace|struct|class|enum)\b")
OPENS_BODY = re.compile(r"\)\s*(const)?\s*(override)?\s*(noexcept)?\s*(->\s*[\w:<>]+)?\s*(:.*)?\{$")


def code_files(root):
    files = []
    for folder in ("src", "apps", "ros"):
        for ext in ("cpp", "h"):
            files += glob.glob(os.path.join(root, folder, "**", "*." + ext), recursive=True)
    return sorted(files)


def signature_start(lines, i):
    """First line of the signature that ends on line i."""
    k = i
    while k > 0:
        prev = lines[k - 1].strip()
        if not prev or prev.endswith((";", "{", "}")) or prev.startswith(("//", "#", "///")):
            break
        k -= 1
    return k


def functions(path):
    """(first line, line count, name) of each function definition in a file."""
    lines = open(path, encoding="utf-8").read().split("\n")
    found, i = [], 0
    while i < len(lines):
        line = lines[i].rstrip()
        if OPENS_BODY.search(line) and not CONTROL.match(line) and not re.search(r"\]\s*\(", line):
            # A constructor's initializer list may start the line that opens the body: its
            # signature is above it.
            k = signature_start(lines, i)
            head = lines[k].strip()
            if CONTROL.match(lines[k]) or "=" in head.split("(")[0]:
                i += 1
                continue
            depth, j = line.count("{") - line.count("}"), i + 1
            while j < len(lines) and depth > 0:
                depth += lines[j].count("{") - lines[j].count("}")
                j += 1
            names = re.findall(r"([\w:~]+)\s*\(", head)
            found.append((k + 1, j - k, names[0] if names else head[:40]))
            i = j
            continue
        i += 1
    return found


def check_functions(root):
    problems, n = [], 0
    for path in code_files(root):
        for line, count, name in functions(path):
            n += 1
            if count > MAX_LINES:
                problems.append(f"{os.path.relpath(path, root)}:{line}: {name} is {count} lines (at most {MAX_LINES})")
    return problems, n


def check_history(root):
    problems, n = [], 0
    for path in code_files(root):
        for number, line in enumerate(open(path, encoding="utf-8"), 1):
            comment = line.split("//", 1)[1] if "//" in line else ""
            n += 1
            for word in re.findall(r"\b[0-9a-f]{7,40}\b", comment):
                if re.search(r"[a-f]", word) and re.search(r"[0-9]", word):
                    problems.append(f"{os.path.relpath(path, root)}:{number}: comment names a commit ({word})")
            for rx, what in HISTORY:
                if rx.search(comment):
                    problems.append(f"{os.path.relpath(path, root)}:{number}: comment {what}: {comment.strip()[:60]}")
    return problems, n


def check_files(root):
    problems, files = [], [f for f in code_files(root) if os.path.relpath(f, root).startswith("src" + os.sep)]
    for path in files:
        n = sum(1 for _ in open(path, encoding="utf-8"))
        if n > MAX_FILE_LINES:
            problems.append(f"{os.path.relpath(path, root)}: {n} lines (at most {MAX_FILE_LINES})")
    return problems, len(files)


def check_format(root):
    tool = shutil.which("clang-format")
    if tool is None:
        return ["clang-format not found: install it (scripts/setup.sh installs Debian's clang-format)"], 0
    files = []
    for folder in FORMATTED:
        for ext in ("cpp", "h"):
            files += glob.glob(os.path.join(root, folder, "**", "*." + ext), recursive=True)
    files = sorted(f for f in files if "node_modules" not in f)
    problems = []
    for path in files:
        done = subprocess.run([tool, "--dry-run", "--Werror", "--style=file", path], capture_output=True, text=True,
                              cwd=root)
        if done.returncode != 0:
            first = next((l for l in done.stderr.splitlines() if "error:" in l), done.stderr.strip()[:120])
            problems.append(f"{os.path.relpath(path, root)}: not as clang-format writes it "
                            f"(clang-format -i --style=file {os.path.relpath(path, root)}): {first.strip()[:100]}")
    return problems, len(files)


CHECKS = {"functions": check_functions, "history": check_history, "files": check_files, "format": check_format}


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in CHECKS:
        print(__doc__)
        return 2
    problems, n = CHECKS[sys.argv[1]](sys.argv[2])
    for p in problems:
        print(p)
    print(f"{sys.argv[1]}: {n} checked, {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
