"""Exceptions raised on user input.

A scene is validated once, when it is loaded; every problem found there is a :class:`SceneError`
that names the dotted key (``tethers.main.EA``), what was expected and what was got, so the user
can fix the file without reading the code.
"""

from __future__ import annotations


class SceneError(ValueError):
    """A scene file or scene dictionary is invalid.

    Attributes:
        key: dotted path of the offending key, e.g. ``"tethers.main.EA"`` or
            ``"bodies.m0.position[1]"``; ``""`` for the document as a whole (a TOML syntax error).
        expected: what the key should hold, e.g. ``"a force (e.g. '5e4 N')"``.
        got: what it held, e.g. ``"'5e4 kg' (dimension mass)"``.
        hint: an optional suggestion appended to the message (a did-you-mean, a fix).
        source: the scene's file path, or ``"<dict>"`` for a scene built from Python.
        line: 1-based line in ``source`` when known (TOML syntax errors), else ``None``.

    It subclasses :class:`ValueError` so callers that only know "bad value" still catch it.
    """

    def __init__(
        self,
        key: str,
        expected: str,
        got: str,
        *,
        hint: str | None = None,
        source: str | None = None,
        line: int | None = None,
    ) -> None:
        self.key = key
        self.expected = expected
        self.got = got
        self.hint = hint
        self.source = source
        self.line = line
        super().__init__(self._message())

    def _message(self) -> str:
        if self.key:
            where = f"scene key {self.key!r}"
        elif self.source is not None:
            where = f"scene file {self.source!r}"
        else:
            where = "scene"
        if self.line is not None:
            where += f" line {self.line}"
        text = f"{where}: expected {self.expected}, got {self.got}"
        if self.hint:
            text += f"; {self.hint}"
        # The file is named last so the message still starts with the key; a scene built from a
        # Python dictionary has no file worth naming.
        if self.key and self.source not in (None, "<dict>"):
            text += f" [in {self.source}]"
        return text

    def with_source(self, source: str) -> "SceneError":
        """A copy of this error that names ``source`` (the loader adds the file after the fact)."""
        return SceneError(
            self.key, self.expected, self.got, hint=self.hint, source=source, line=self.line
        )

    def __reduce__(self):
        # Keyword-only fields would be lost by the default exception pickling, and studies run
        # scenes in worker processes that send errors back.
        return (_rebuild_scene_error, (self.key, self.expected, self.got, self.hint, self.source, self.line))


def _rebuild_scene_error(key, expected, got, hint, source, line) -> SceneError:
    return SceneError(key, expected, got, hint=hint, source=source, line=line)
