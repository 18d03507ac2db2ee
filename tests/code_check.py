#!/usr/bin/env python3
"""Checks house rules on the code (docs/architecture.md, ../shared/STYLE.md).

  code_check.py functions ROOT  no function in src/, apps/ and ros/ is longer than 60 lines
                                (signature to closing brace; lambdas count in their function)
  code_check.py history ROOT    no comment in src/, apps/ and ros/ names a commit (7-40 hex digits
                                with a letter): history belongs in commit messages and docs/

Prints one line per problem and exits 1 if there is any.
"""
import glob
import os
import re
import sys

MAX_LINES = 60
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
        if OPENS_BODY.search(line) and not CONTROL.match(line) and not re.search(r"\]\s*\(", line) \
                and not line.strip().startswith(":"):
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
    return problems, n


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in ("functions", "history"):
        print(__doc__)
        return 2
    problems, n = (check_functions if sys.argv[1] == "functions" else check_history)(sys.argv[2])
    for p in problems:
        print(p)
    print(f"{sys.argv[1]}: {n} checked, {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
