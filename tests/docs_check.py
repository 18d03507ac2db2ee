#!/usr/bin/env python3
"""Checks that the README and docs/ say only what is true of the code.

  docs_check.py commands IDYVINS ROOT  every `idyvins <subcommand> ... --option` written in
                                       README.md and docs/*.md is accepted: the subcommand's
                                       --help runs and lists each option
  docs_check.py links ROOT             every relative link and image in README.md and docs/*.md
                                       resolves to a file (and its #anchor to a heading); every
                                       PNG in docs/ is at most 200 KB
  docs_check.py periods ROOT           no line of README, docs, code, tests or scripts names a
                                       work period by number; history is named by commit
  docs_check.py anywhere ROOT IDYVINS  every command of README.md's ```sh blocks names the checkout's
                                       files through $IDY (build/, config/, ...) and writes outside it,
                                       and the quick start's `info` runs from another folder so written
  docs_check.py snippets ROOT          every ```cpp block of README.md and docs/*.md is a verbatim
                                       excerpt (consecutive lines) of a file in docs/examples/, which
                                       a test builds against the installed package

Prints one line per problem and exits 1 if there is any.
"""
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile


def doc_files(root):
    return [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "*.md")))


def command_texts(text):
    """Each `idyvins <sub> ...` invocation: its subcommand and the text of its arguments.
    Looks in inline code spans and in fenced code blocks (joining `\\` continuations)."""
    chunks = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S):
        chunks += block.replace("\\\n", " ").split("\n")
    prose = re.sub(r"```[a-z]*\n.*?```", "", text, flags=re.S)
    chunks += re.findall(r"`([^`\n]+)`", prose)
    found = []
    for chunk in chunks:
        chunk = chunk.split("#")[0] if not chunk.lstrip().startswith("#include") else ""
        chunk = re.sub(r"\b(roslaunch|rospack|rosrun) idyvins\b", r"\1 IDYVINS_ROS_PACKAGE", chunk)  # the ROS package
        for m in re.finditer(r"(?:^|[\s/])idyvins (?!::)([a-z][a-z-]*)\b(.*?)(?=(?:[\s/]idyvins )|$)", chunk):
            found.append((m.group(1), m.group(2)))
    return found


def subcommands(binary):
    """The subcommand names listed by `idyvins --help`."""
    out = subprocess.run([binary, "--help"], capture_output=True, text=True).stdout
    parts = re.split(r"^Subcommands:\s*$", out, flags=re.M | re.I)
    listing = parts[-1] if len(parts) > 1 else ""
    return set(re.findall(r"^  ([a-z][a-z-]*) ", listing, flags=re.M))


def check_commands(binary, root):
    problems, helps = [], {}
    known = subcommands(binary)
    if not known:
        problems.append(f"{binary} --help lists no subcommands")
    for path in doc_files(root):
        text = open(path, encoding="utf-8").read()
        for sub, args in command_texts(text):
            if sub not in helps and sub in known:
                r = subprocess.run([binary, sub, "--help"], capture_output=True, text=True)
                helps[sub] = r.stdout if r.returncode == 0 else None
            rel = os.path.relpath(path, root)
            if sub not in known or helps[sub] is None:
                problems.append(f"{rel}: 'idyvins {sub}' is not a subcommand")
                continue
            for opt in re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", args):
                if not re.search(r"(?<![\w-])" + re.escape(opt) + r"(?![\w-])", helps[sub]):
                    problems.append(f"{rel}: 'idyvins {sub}' has no option {opt}")
    if not helps:
        problems.append("no idyvins command found in the docs (the parser is broken)")
    return problems, len(helps)


def slug(heading):
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to dashes."""
    s = heading.strip().lower()
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def check_links(root):
    problems, count = [], 0
    for path in doc_files(root):
        text = open(path, encoding="utf-8").read()
        text_no_code = re.sub(r"```.*?```", "", text, flags=re.S)
        for target in re.findall(r"!?\[[^\]]*\]\(([^)\s]+)\)", text_no_code):
            if re.match(r"[a-z]+://", target) or target.startswith("mailto:"):
                continue
            count += 1
            file_part, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
            rel = os.path.relpath(path, root)
            if not os.path.exists(dest):
                problems.append(f"{rel}: link to {target}: no such file")
                continue
            if anchor and dest.endswith(".md"):
                headings = re.findall(r"^#+ (.*)$", open(dest, encoding="utf-8").read(), flags=re.M)
                if anchor not in {slug(h) for h in headings}:
                    problems.append(f"{rel}: link to {target}: no heading with that anchor")
    for png in sorted(glob.glob(os.path.join(root, "docs", "*.png"))):
        if os.path.getsize(png) > 200 * 1024:
            problems.append(f"{os.path.relpath(png, root)}: {os.path.getsize(png)} bytes (at most 200 KB)")
    return problems, count


def check_periods(root):
    problems = []
    files = doc_files(root)
    for pattern in ("src/**/*", "apps/**/*", "tests/**/*", "bench/**/*", "scripts/**/*", "config/**/*"):
        files += [f for f in glob.glob(os.path.join(root, pattern), recursive=True) if os.path.isfile(f)]
    files += [os.path.join(root, "Makefile")] if os.path.exists(os.path.join(root, "Makefile")) else []
    word = "sess" + "ion"  # spelled so that this file does not match itself
    rx = re.compile(r"\b" + word + r"s?[ -]\d", re.I)
    for f in files:
        try:
            lines = open(f, encoding="utf-8").read().split("\n")
        except UnicodeDecodeError:
            continue
        for i, line in enumerate(lines, 1):
            if rx.search(line):
                problems.append(f"{os.path.relpath(f, root)}:{i}: names a work period: {line.strip()[:80]}")
    return problems, len(files)


def check_snippets(root):
    examples = {}
    for path in sorted(glob.glob(os.path.join(root, "docs", "examples", "*.cpp"))):
        examples[os.path.relpath(path, root)] = [l.rstrip() for l in open(path, encoding="utf-8")]
    problems, n = [], 0
    for doc in doc_files(root):
        text = open(doc, encoding="utf-8").read()
        for m in re.finditer(r"```cpp\n(.*?)```", text, flags=re.S):
            n += 1
            block = [l.rstrip() for l in m.group(1).rstrip("\n").split("\n")]
            line = text[:m.start()].count("\n") + 1
            # Lines may be dedented in the docs: compare without the common indentation.
            def found_in(lines):
                stripped = [l.strip() for l in lines]
                want = [l.strip() for l in block]
                return any(stripped[i:i + len(want)] == want for i in range(len(stripped) - len(want) + 1))
            if not any(found_in(lines) for lines in examples.values()):
                problems.append(f"{os.path.relpath(doc, root)}:{line}: C++ block is not an excerpt of docs/examples/*.cpp")
    return problems, n


REPO_PATH = re.compile(r"(?<![\w/$.~-])(build|config|scripts|bench|docs|out|data_sim|tests|web)/")


def check_anywhere(root, binary):
    """README's shell commands work from any folder: repository paths through $IDY, outputs outside."""
    text = open(os.path.join(root, "README.md"), encoding="utf-8").read()
    problems, n = [], 0
    info = None
    for m in re.finditer(r"```sh\n(.*?)```", text, flags=re.S):
        first = text[:m.start()].count("\n") + 2
        for k, line in enumerate(m.group(1).split("\n")):
            command = line.split("#")[0]
            if not command.strip() or command.strip().startswith("make "):
                continue
            n += 1
            bare = [p.group(0) for p in REPO_PATH.finditer(command)]
            if bare:
                problems.append(f"README.md:{first + k}: {', '.join(bare)} is relative to the checkout: write $IDY/...")
            if " info " in command and info is None:
                info = command
    if info is None:
        problems.append("README.md: no `idyvins info` command to try from another folder")
        return problems, n
    # The first `info` from a scratch folder, on the shared EuRoC excerpt in place of the user's data.
    words = info.replace("$IDY", os.path.abspath(root)).split()
    words[words.index("info") + 1] = os.path.join(os.path.abspath(root), "..", "shared", "data", "euroc_v101_micro")
    words[0] = os.path.abspath(binary)
    scratch = tempfile.mkdtemp()
    r = subprocess.run(words, cwd=scratch, capture_output=True, text=True)
    if r.returncode != 0:
        problems.append(f"README.md: {info.strip()} from {scratch}: exit {r.returncode}: {r.stderr.strip()[-200:]}")
    shutil.rmtree(scratch, ignore_errors=True)
    return problems, n


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    what = sys.argv[1]
    if what == "commands":
        problems, n = check_commands(sys.argv[2], sys.argv[3])
        summary = f"{n} subcommands named in the docs"
    elif what == "links":
        problems, n = check_links(sys.argv[2])
        summary = f"{n} relative links"
    elif what == "periods":
        problems, n = check_periods(sys.argv[2])
        summary = f"{n} files"
    elif what == "anywhere":
        problems, n = check_anywhere(sys.argv[2], sys.argv[3])
        summary = f"{n} README commands"
    elif what == "snippets":
        problems, n = check_snippets(sys.argv[2])
        summary = f"{n} C++ blocks"
    else:
        print(__doc__)
        return 2
    for p in problems:
        print(p)
    print(f"{summary}: {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
