#!/usr/bin/env python3
"""The longest functions of the C++ sources, in lines from signature to closing brace.

    scripts/function_lengths.py [COUNT]        # default: the 10 longest

A function is a brace block opened at namespace or class level after a closing parenthesis
(a definition), lambdas and nested blocks included in their function. Comments and string
literals are skipped. Good enough to keep functions short; not a C++ parser.
"""
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
FOLDERS = ["common", "model", "workspace", "identify", "sensors", "design", "montecarlo", "cli", "python"]
SIGNATURE_END = re.compile(r"\)\s*(const)?\s*(noexcept)?\s*(override)?\s*(->[^{;]*)?(:[^{;]*)?$", re.S)


def strip(text):
    """Comments and string/char literals blanked, newlines kept."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(path):
    text = strip(path.read_text(encoding="utf-8", errors="replace"))
    stack = []  # per open brace: "scope" (namespace, class, extern) or (name, start line) or "block"
    head_start = 0  # where the text before the next brace begins
    line = 1
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
        elif c == "{":
            head = text[head_start:i]
            in_function = any(isinstance(s, tuple) for s in stack)
            if in_function:
                stack.append("block")
            elif re.search(r"\b(namespace|class|struct|union|enum|extern)\b[^;()]*$", head) or head.strip().endswith("="):
                stack.append("scope")
            elif SIGNATURE_END.search(head.strip()):
                start = line - head.strip().count("\n") - (0 if head.strip() else 0)
                name = re.findall(r"([\w:~<>]+)\s*\(", head)
                stack.append((name[0] if name else "?", start))
            else:
                stack.append("block")
            head_start = i + 1
        elif c == "}":
            top = stack.pop() if stack else "scope"
            if isinstance(top, tuple):
                yield top[0], top[1], line
            head_start = i + 1
        elif c == ";":
            head_start = i + 1


def main():
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    found = []
    for folder in FOLDERS:
        for path in sorted((ROOT / folder).glob("*.[ch]*")):
            if path.suffix not in (".h", ".cc", ".in"):
                continue
            for name, start, end in functions(path):
                found.append((end - start + 1, f"{path.relative_to(ROOT)}:{start}", name))
    for length, where, name in sorted(found, reverse=True)[:count]:
        print(f"{length:5d}  {where:40s} {name}")


if __name__ == "__main__":
    main()
