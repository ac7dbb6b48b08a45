#!/usr/bin/env python3
"""Lengths of the functions and rooms (a .cpp with its .h) in C++ sources, found by matching braces.

    scripts/function_lengths.py [--over N] [--rooms] [folders or files...]

Prints one line per function of more than N lines (default 80), longest first:
`lines  file:line  name`. A function is counted from the first line of its signature to its closing
brace; lambdas and local classes count with the function they are in. With --rooms it also prints each
room over 600 lines. Exits 1 when a function is over 100 lines or a room over 600.
Default folders: the product folders of app/, xr/, render/, interaction/ and python/src.
"""
import argparse
import os
import re
import sys

DEFAULT_FOLDERS = ["app", "xr", "render", "interaction", "python/src"]
SUFFIXES = (".cpp", ".h", ".hpp", ".cu", ".cuh", ".cc")
FUNCTION_LIMIT = 100
ROOM_LIMIT = 600


def strip_comments_and_literals(text):
    """The text with comments, string and character literals blanked (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c == 'R' and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            k = text.find("(", i + 2)
            delim = ")" + text[i + 2:k] + '"'
            j = text.find(delim, k)
            j = n if j < 0 else j + len(delim)
            out.append('""' + "".join(ch if ch == "\n" else " " for ch in text[i + 2:j]))
            i = j
        elif c in "\"'":
            # A digit separator (1'000) is not a character literal.
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum() \
                    and re.match(r"[0-9a-fA-FxXbB']*$", text[max(0, i - 1):i]):
                out.append(c)
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (min(j, n) - i - 1) + (c if j < n else ""))
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def classify(header):
    """What a `{` opens, from the text since the previous `;`, `{` or `}` at the same depth."""
    h = " ".join(header.split())
    h = re.sub(r"^(#.*?\s)+", "", h)
    if not h:
        return "block"
    if re.match(r"^(inline\s+)?namespace\b", h) or re.match(r'^extern\s*""', h):
        return "namespace"
    if re.match(r"^(template\s*<.*>\s*)?(class|struct|union|enum)\b", h) and "(" not in h.split("{")[0]:
        return "class"
    if "(" not in h:
        return "data"
    before_paren = h.split("(", 1)[0]
    if "=" in before_paren and "operator" not in before_paren:
        return "data"
    if re.search(r"\)\s*(const|noexcept|override|final|mutable|&|&&|\s)*(->\s*[\w:<>,\s\*&]+)?$", h):
        return "function"
    if re.search(r"\)\s*(const|noexcept|\s)*:\s*[^:]", h):
        return "function-init"  # a constructor whose initialiser list may hold brace-inits
    return "data"


def function_name(header):
    """The name before the first `(` that is not inside a template's angle brackets."""
    depth = 0
    for k, ch in enumerate(header):
        if ch == "<" and not header[:k].rstrip().endswith("operator"):
            depth += 1
        elif ch == ">" and depth > 0:
            depth -= 1
        elif ch == "(" and depth == 0:
            names = re.findall(r"(operator\s*\S+|[~\w:]+)\s*$", header[:k])
            return names[-1] if names else "?"
    return "?"


def functions_of(path):
    text = open(path, encoding="utf-8", errors="replace").read()
    code = strip_comments_and_literals(text)
    line_of = []
    line = 1
    for ch in code:
        line_of.append(line)
        if ch == "\n":
            line += 1
    found = []
    stack = []  # (kind, start index of header, name)
    header_start = 0
    i = 0
    while i < len(code):
        ch = code[i]
        if ch == "{":
            in_function = any(k in ("function",) for k, _, _ in stack)
            if in_function:
                stack.append(("inner", i, ""))
            else:
                header = code[header_start:i]
                kind = classify(header)
                if kind == "function-init":
                    # `m_x{...}` inside an initialiser list: the identifier just before the brace.
                    if re.search(r"[\w>]\s*$", header) and not re.search(r"\)\s*$", header):
                        stack.append(("init", header_start, ""))
                        i += 1
                        continue
                    kind = "function"
                if kind == "function":
                    first = len(header) - len(header.lstrip())
                    name = function_name(header)
                    stack.append(("function", header_start + first, name))
                else:
                    stack.append((kind, i, ""))
            header_start = i + 1
        elif ch == "}":
            if stack:
                kind, start, name = stack.pop()
                if kind == "function":
                    found.append((line_of[i] - line_of[start] + 1, line_of[start], name))
                if kind == "init":
                    i += 1
                    continue  # the header of the constructor goes on
            header_start = i + 1
        elif ch == ";" and not any(k in ("function", "inner") for k, _, _ in stack):
            header_start = i + 1
        elif ch == ":" and not any(k in ("function", "inner") for k, _, _ in stack):
            # `public:` / `private:` labels end a header.
            if re.search(r"\b(public|private|protected)\s*$", code[header_start:i]):
                header_start = i + 1
        i += 1
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="*", default=DEFAULT_FOLDERS)
    parser.add_argument("--over", type=int, default=80)
    parser.add_argument("--rooms", action="store_true")
    args = parser.parse_args()
    rows, rooms = [], {}
    for folder in args.folders:
        walk = [(os.path.dirname(folder), [], [os.path.basename(folder)])] if os.path.isfile(folder) else os.walk(folder)
        for root, _, files in walk:
            for f in sorted(files):
                if not f.endswith(SUFFIXES):
                    continue
                path = os.path.join(root, f)
                for length, line, name in functions_of(path):
                    rows.append((length, f"{path}:{line}", name))
                room = os.path.splitext(f)[0]
                key = (folder, room)
                with open(path, encoding="utf-8", errors="replace") as fh:
                    rooms.setdefault(key, []).append((path, sum(1 for _ in fh)))
    failed = False
    for length, where, name in sorted(rows, reverse=True):
        if length > args.over:
            print(f"{length:5d}  {where}  {name}")
        failed |= length > FUNCTION_LIMIT
    for (folder, room), parts in sorted(rooms.items()):
        total = sum(n for _, n in parts)
        if args.rooms and total > ROOM_LIMIT:
            print(f"room {total:5d}  {' + '.join(p for p, _ in parts)}")
        failed |= total > ROOM_LIMIT
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
