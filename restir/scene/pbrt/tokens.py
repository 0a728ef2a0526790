"""The tokens of a pbrt-v4 scene file: quoted strings, brackets, and bare words (directives, numbers,
`true`/`false`), with `#` comments to the end of the line. Each token carries its file and line,
for errors that name them.

A bracketed list of numbers is read in one step (numpy's parser over the text between the
brackets): meshes written inline hold most of a file's tokens, and reading them one by one was
the bulk of a load.
"""
import re

import numpy as np

from ..errors import SceneError
from ..scene_file import read_scene_file

_TOKEN = re.compile(r'"(?:[^"\\\n]|\\.)*"|\[|\]|[^\s\[\]"#]+|#[^\n]*|"')
_ESCAPES = {"n": "\n", "t": "\t", "b": "\b", "f": "\f", "r": "\r", "\\": "\\", "'": "'", '"': '"'}


class Token:
    __slots__ = ("text", "line", "quoted")

    def __init__(self, text: str, line: int, quoted: bool):
        self.text, self.line, self.quoted = text, line, quoted


def read_text(path: str) -> str:
    """The file's text (scene_file.read_scene_file's checks first)."""
    data = read_scene_file(path)
    if data.startswith(b"\x1f\x8b"):
        raise SceneError("gzip-compressed pbrt files are not supported: decompress it first", path)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise SceneError(f"not a text file (byte {e.start} is not UTF-8)", path) from None


def unescape(body: str, loc: str) -> str:
    if "\\" not in body:
        return body
    out, i = [], 0
    while i < len(body):
        c = body[i]
        if c == "\\":
            e = body[i + 1]
            if e not in _ESCAPES:
                raise SceneError(f"unknown escape sequence '\\{e}' in a string", loc)
            out.append(_ESCAPES[e])
            i += 2
        else:
            out.append(c)
            i += 1
    return "".join(out)


class Tokenizer:
    """Tokens of one file, in order; `next()` returns None at the end."""

    def __init__(self, path: str, text: str | None = None):
        self.path = path
        self.text = read_text(path) if text is None else text
        self.pos = 0
        self.line = 1
        self.pushed: list[Token] = []

    def loc(self, line: int | None = None) -> str:
        return f"{self.path}:{self.line if line is None else line}"

    def next(self) -> Token | None:
        if self.pushed:
            return self.pushed.pop()
        text = self.text
        while True:
            m = _TOKEN.search(text, self.pos)
            if m is None:
                self.line += text.count("\n", self.pos)
                self.pos = len(text)
                return None
            self.line += text.count("\n", self.pos, m.start())
            self.pos = m.end()
            s = m.group()
            if s[0] == "#":
                continue
            if s[0] == '"':
                if len(s) == 1 or s[-1] != '"':
                    raise SceneError("unterminated string", self.loc())
                return Token(unescape(s[1:-1], self.loc()), self.line, True)
            return Token(s, self.line, False)

    def push(self, tok: Token) -> None:
        self.pushed.append(tok)

    def numbers_until_bracket(self) -> np.ndarray | None:
        """After a '[': when the list holds only numbers (no string, no comment), all of them
        up to the ']' (consumed) as float64; else None, and nothing is consumed."""
        if self.pushed:
            return None
        end = self.text.find("]", self.pos)
        if end < 0:
            return None
        body = self.text[self.pos:end]
        if '"' in body or "#" in body or "[" in body:
            return None
        words = body.split()
        try:
            values = np.array(words, dtype=np.float64) if words else np.zeros(0)
        except ValueError:
            return None
        self.line += body.count("\n")
        self.pos = end + 1
        return values
