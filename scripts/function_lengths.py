#!/usr/bin/env python3
"""List the C++ functions longer than a threshold, one `file:line name length` a line.

A function's length counts its lines from the first line of its signature to its closing
brace. Lambdas, local structs and blocks count toward the function that encloses them;
member functions defined inside a class body count on their own.

The scan is a brace counter over the source with comments, string and character literals
and preprocessor lines blanked out, not a C++ parser: it recognises the definitions fgcal
writes (free and member functions, constructors with initializer lists, operators,
lambdas assigned at namespace scope), which is what a length check needs.

    scripts/function_lengths.py                    # apps/, threshold 80
    scripts/function_lengths.py --threshold 60 core/src apps/src/report/report.cpp

Prints the longest first, a count on stderr, and exits 1 when any function is
over the threshold (0 when none is), so a check can run it as it is.
"""
import argparse
import pathlib
import re
import sys

SOURCE_SUFFIXES = {".cpp", ".hpp", ".h", ".cc", ".cxx", ".hh", ".ipp", ".inl"}
CLASS_KEY = re.compile(r"\b(class|struct|union|enum)\b")
IDENT_CHAR = re.compile(r"[A-Za-z0-9_]")


def blank_out(text):
    """Returns text with comments, literals and preprocessor lines replaced by spaces.

    Newlines are kept so positions still map to the same lines."""
    out = []
    i, n = 0, len(text)
    at_line_start = True
    while i < n:
        c = text[i]
        if at_line_start and c == "#":
            # A directive runs to the end of the line, continued by a trailing backslash.
            while i < n and not (text[i] == "\n" and text[i - 1] != "\\"):
                out.append("\n" if text[i] == "\n" else " ")
                i += 1
            continue
        if c == "\n":
            at_line_start = True
            out.append(c)
            i += 1
            continue
        if not c.isspace():
            at_line_start = False
        if text.startswith("//", i):
            while i < n and text[i] != "\n":
                out.append(" ")
                i += 1
            continue
        if text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            out.extend("\n" if ch == "\n" else " " for ch in text[i:end])
            i = end
            continue
        raw = re.match(r'(?:u8|[uUL])?R"([^(\s]*)\(', text[i:i + 40])
        if raw and (i == 0 or not IDENT_CHAR.match(text[i - 1])):
            end = text.find(")" + raw.group(1) + '"', i + raw.end())
            end = n if end < 0 else end + len(raw.group(1)) + 2
            out.append('""')
            out.extend("\n" if ch == "\n" else " " for ch in text[i + 2:end])
            i = end
            continue
        if c == '"' or (c == "'" and not (i > 0 and re.match(r"[0-9A-Fa-f]", text[i - 1])
                                         and i + 1 < n and re.match(r"[0-9A-Fa-f]", text[i + 1]))):
            # A string or character literal (a ' between hex digits is a digit separator).
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * max(0, min(j, n) - i - 1) + (c if j < n else ""))
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def strip_template_prefix(head):
    """Drops leading `template <...>` clauses from a declaration head."""
    while True:
        m = re.match(r"\s*template\s*<", head)
        if not m:
            return head
        depth, j = 1, m.end()
        while j < len(head) and depth:
            depth += {"<": 1, ">": -1}.get(head[j], 0)
            j += 1
        head = head[j:]


def first_top_level(head, char):
    """Index of the first `char` in head outside parentheses, brackets and angle pairs."""
    depth = 0
    for j, c in enumerate(head):
        if c in "([":
            depth += 1
        elif c in ")]":
            depth -= 1
        elif c == char and depth == 0:
            return j
    return -1


def classify(head):
    """Says what a `{` opening after `head` at namespace or class scope begins.

    Returns ("container", None), ("function", name) or ("initializer", None)."""
    body = strip_template_prefix(head).strip()
    if re.match(r"(inline\s+)?namespace\b", body) or re.match(r"extern\b", body):
        return "container", None
    paren = body.find("(")
    key = CLASS_KEY.search(body)
    if key and (paren < 0 or key.start() < paren):
        return "container", None
    if paren < 0:
        return "initializer", None
    operator = re.search(r"\boperator\b\s*(\(\s*\)|[^(\s]+)?", body)
    equals = first_top_level(body, "=")
    if operator is None and 0 <= equals < paren:
        # `auto f = [](...) {` defines a lambda; anything else is a variable's initializer.
        if re.search(r"\]\s*\(", body[equals:]):
            return "function", body[:equals].split()[-1]
        return "initializer", None
    if operator is not None:
        return "function", _operator_name(body, operator)
    name = body[:paren].split()
    return "function", (name[-1] if name else "?")


def _operator_name(body, operator):
    start = body.rfind(" ", 0, operator.start()) + 1
    return re.sub(r"\s+", "", body[start:operator.end()])


def is_member_initializer(head):
    """True when head ends inside a constructor's initializer list, as in `: x_{`."""
    body = strip_template_prefix(head).rstrip()
    close = body.rfind(")")
    if close < 0 or not body or not (IDENT_CHAR.match(body[-1]) or body[-1] == ">"):
        return False
    rest = body[close + 1:]
    return re.search(r"(?<!:):(?!:)", rest) is not None


def functions_in(path):
    """Yields (line, name, length) for every function defined in the file at path."""
    text = blank_out(path.read_text(errors="replace"))
    line_of = []
    line = 1
    for c in text:
        line_of.append(line)
        line += c == "\n"
    stack = []  # entries: [kind, name, start offset]
    head_start = 0  # where the current declaration head begins at container scope
    paren_depth = 0
    for i, c in enumerate(text):
        in_container = all(kind == "container" for kind, _, _ in stack)
        if c == "{":
            if not in_container:
                stack.append(["block", None, i])
                continue
            head = text[head_start:i]
            if paren_depth > 0 or is_member_initializer(head):
                stack.append(["initializer", None, i])
                continue
            kind, name = classify(head)
            start = head_start + (len(head) - len(head.lstrip()))
            stack.append([kind, name, start])
            if kind == "container":
                head_start, paren_depth = i + 1, 0
        elif c == "}":
            if not stack:
                continue
            kind, name, start = stack.pop()
            if kind == "function":
                first = line_of[start]
                yield first, name, line_of[i] - first + 1
            if kind in ("function", "container") and all(k == "container" for k, _, _ in stack):
                head_start, paren_depth = i + 1, 0
        elif in_container:
            if c == "(":
                paren_depth += 1
            elif c == ")":
                paren_depth -= 1
            elif c == ";" and paren_depth == 0:
                head_start = i + 1


def source_files(paths):
    for p in paths:
        p = pathlib.Path(p)
        if p.is_dir():
            yield from sorted(f for f in p.rglob("*") if f.suffix in SOURCE_SUFFIXES and f.is_file())
        elif p.is_file():
            yield p


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="*", default=["apps"],
                        help="files or folders to scan (default: apps)")
    parser.add_argument("--threshold", type=int, default=80,
                        help="print functions longer than this many lines (default: 80)")
    args = parser.parse_args()
    found = []
    scanned = 0
    for f in source_files(args.paths):
        for line, name, length in functions_in(f):
            scanned += 1
            if length > args.threshold:
                found.append((f, line, name, length))
    for f, line, name, length in sorted(found, key=lambda r: (-r[3], str(r[0]), r[1])):
        print(f"{f}:{line} {name} {length}")
    print(f"{len(found)} of {scanned} functions over {args.threshold} lines", file=sys.stderr)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
