"""Reading YAML/JSON documents with the line of every value, so errors can say where."""

from __future__ import annotations

import json
import re
import sys
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import yaml

from causalplan.causal.diagnostics import Diagnostic, Location, error

PathKey = tuple[str | int, ...]

MAX_DOCUMENT_BYTES = 1_000_000
SAFE_LOADER: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
"""libyaml's safe loader where PyYAML has it: much faster than the pure-Python one."""


class DuplicateKeyError(ValueError):
    """A mapping names the same key twice, at ``line`` (1-based) and ``index`` (0-based, in characters).

    Both are None when unknown: ``json``'s hook sees the key but not where it stands.
    """

    def __init__(self, key: object, line: int | None = None, index: int | None = None) -> None:
        super().__init__(f"duplicate key {key!r}")
        self.key = key
        self.line = line
        self.index = index


class NumberTooLongError(ValueError):
    """An integer has more digits than Python reads from text (``sys.get_int_max_str_digits``, 4,300).

    ``line`` (1-based) is where it stands, when known. Python's own ValueError would otherwise
    escape every reader as a traceback: no document here needs such a number.
    """

    def __init__(self, digits: int, line: int | None = None) -> None:
        self.digits = digits
        self.line = line
        where = f" at line {line}" if line is not None else ""
        super().__init__(f"a number of {digits:,} digits{where} (at most {max_integer_digits():,} can be read)")


def max_integer_digits() -> int:
    """Return how many digits an integer read from text may have (Python's limit; 0 there means none)."""
    return sys.get_int_max_str_digits() or sys.maxsize


def read_integer(digits: str) -> int:
    """``json``'s ``parse_int``: the integer, or NumberTooLongError (no line yet) beyond Python's limit."""
    try:
        return int(digits)
    except ValueError:
        raise NumberTooLongError(len(digits.lstrip("-"))) from None


def load_json(text: str) -> object:
    """Return the JSON value in ``text``, refusing a key named twice and a number too long to read.

    DuplicateKeyError and NumberTooLongError (with its line) say which; json.JSONDecodeError the rest.
    """
    try:
        return json.loads(text, object_pairs_hook=refuse_duplicate_keys, parse_int=read_integer)
    except NumberTooLongError as exc:
        raise located_long_number(text, exc) from None


def located_long_number(text: str, exc: NumberTooLongError) -> NumberTooLongError:
    """Return ``exc`` with the line of the first run of that many digits in ``text``, when found."""
    found = re.search(rf"\d{{{exc.digits}}}", text)
    if found is None:
        return exc
    return NumberTooLongError(exc.digits, text.count("\n", 0, found.start()) + 1)


class _UniqueKeyLoader(SAFE_LOADER):  # type: ignore[misc, valid-type]
    """The safe loader, refusing a mapping that names a key twice (PyYAML keeps the last one), and
    an integer too long to read (NumberTooLongError with its line, not PyYAML's bare ValueError)."""

    def construct_long_checked_int(self, node: yaml.ScalarNode) -> int:
        try:
            value: int = self.construct_yaml_int(node)
        except ValueError:
            digits = sum(character.isdigit() for character in str(node.value))
            raise NumberTooLongError(digits, node.start_mark.line + 1) from None
        return value

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[object, object]:
        seen: set[object] = set()
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue  # '<<' merges another mapping in: its keys may be overridden on purpose
            key = self.construct_object(key_node, deep=deep)
            try:
                is_repeated = key in seen
            except TypeError:  # an unhashable key: construct_mapping below reports it
                continue
            if is_repeated:
                raise DuplicateKeyError(key, key_node.start_mark.line + 1, key_node.start_mark.index)
            seen.add(key)
        mapping: dict[object, object] = super().construct_mapping(node, deep=deep)
        return mapping


_UniqueKeyLoader.add_constructor("tag:yaml.org,2002:int", _UniqueKeyLoader.construct_long_checked_int)


def load_yaml_refusing_duplicates(text: str) -> object:
    """Return the YAML (or JSON) document in ``text``; DuplicateKeyError names a key written twice and its line."""
    return yaml.load(text, Loader=_UniqueKeyLoader)


def refuse_duplicate_keys(pairs: list[tuple[str, object]]) -> dict[str, object]:
    """``json``'s ``object_pairs_hook``: the object, or DuplicateKeyError for a key named twice (no line yet).

    Whatever reads JSON documents people send (files here, request bodies in the service) uses
    it, so a repeated key is refused everywhere instead of the last one silently winning.
    """
    result: dict[str, object] = {}
    for key, value in pairs:
        if key in result:
            raise DuplicateKeyError(key)
        result[key] = value
    return result


def located_duplicate_key(text: str, exc: DuplicateKeyError) -> DuplicateKeyError:
    """Return ``exc`` with the line and index of its second key in ``text`` (JSON read as YAML), when found.

    Tabs become spaces first (one for one, so lines and indexes stay): JSON allows them between
    tokens, YAML does not.
    """
    try:
        load_yaml_refusing_duplicates(text.replace("\t", " "))
    except DuplicateKeyError as located:
        if located.key == exc.key:
            return located
    except (yaml.YAMLError, RecursionError, NumberTooLongError):
        pass
    return exc


def _long_number(file_name: str | None, exc: NumberTooLongError) -> tuple[object, SourceMap, list[Diagnostic]]:
    return _unreadable(
        file_name,
        error(
            "number_too_long",
            f"The document holds a number of {exc.digits:,} digits; at most {max_integer_digits():,} can be read.",
            Location(file=file_name, line=exc.line),
            "No model, mapping or trial needs such a number: remove it, or write it in quotes.",
        ),
    )


def _duplicate_key(file_name: str | None, exc: DuplicateKeyError) -> tuple[object, SourceMap, list[Diagnostic]]:
    where = f" at line {exc.line}" if exc.line is not None else ""
    return _unreadable(
        file_name,
        error(
            "duplicate_key",
            f"The key {exc.key!r} appears twice in one mapping{where}; only one may stay.",
            Location(file=file_name, line=exc.line),
            "Merge the two entries into one, or rename one of them.",
        ),
    )


@dataclass(frozen=True)
class SourceMap:
    """The file a document came from and the 1-based line of each value, by path.

    The lines are worked out from ``text`` only when a location is first asked for: valid
    documents (the built-in catalog on every start) never pay for it.
    """

    file: str | None = None
    text: str | None = field(default=None, repr=False, compare=False)

    @cached_property
    def lines(self) -> dict[PathKey, int]:
        """Return the 1-based line of each value, by path (empty when there is no text)."""
        return _line_map(self.text) if self.text else {}

    def locate(self, *path: str | int, rule: int | None = None, part: str | None = None) -> Location:
        """Return the location of ``path``, falling back to its nearest located parent."""
        key: PathKey = tuple(path)
        while key and key not in self.lines:
            key = key[:-1]
        return Location(file=self.file, line=self.lines.get(key), rule=rule, part=part)


def _record_lines(node: yaml.Node, path: PathKey, lines: dict[PathKey, int], seen: set[int]) -> None:
    lines[path] = node.start_mark.line + 1
    if id(node) in seen:  # an alias: its target's lines are recorded once, where it is defined
        return
    seen.add(id(node))
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            if isinstance(key_node, yaml.ScalarNode):
                child = (*path, key_node.value)
                _record_lines(value_node, child, lines, seen)
                lines[child] = key_node.start_mark.line + 1
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _record_lines(item, (*path, index), lines, seen)


def _line_map(text: str) -> dict[PathKey, int]:
    try:
        root = yaml.compose(text, Loader=SAFE_LOADER)
    except (yaml.YAMLError, RecursionError):
        return {}
    lines: dict[PathKey, int] = {}
    if root is not None:
        _record_lines(root, (), lines, set())
    return lines


def _looks_like_json(text: str, file_name: str | None) -> bool:
    suffix = file_name.lower().rsplit(".", 1)[-1] if file_name and "." in file_name else ""
    if suffix in ("yaml", "yml"):
        return False
    return suffix == "json" or text.lstrip().startswith(("{", "["))


def _unreadable(file_name: str | None, problem: Diagnostic) -> tuple[object, SourceMap, list[Diagnostic]]:
    """Return what reading a document gives when ``problem`` stops it: no data, no lines."""
    return None, SourceMap(file_name), [problem]


def _too_deep(file_name: str | None) -> tuple[object, SourceMap, list[Diagnostic]]:
    return _unreadable(
        file_name,
        error(
            "syntax_error",
            "The document is nested too deeply to read.",
            Location(file=file_name),
            "A model or mapping needs only a few levels: object, functions, rules.",
        ),
    )


def parse_text(text: str, file_name: str | None = None) -> tuple[object, SourceMap, list[Diagnostic]]:
    """Parse YAML or JSON text; return the data, its line map and any syntax error."""
    text = text.removeprefix("\ufeff")
    if _looks_like_json(text, file_name):
        try:
            data = load_json(text)
        except DuplicateKeyError as exc:
            return _duplicate_key(file_name, located_duplicate_key(text, exc))
        except NumberTooLongError as exc:
            return _long_number(file_name, exc)
        except RecursionError:
            return _too_deep(file_name)
        except json.JSONDecodeError as exc:
            return _unreadable(
                file_name,
                error(
                    "syntax_error",
                    f"The JSON is malformed at line {exc.lineno}, column {exc.colno}: {exc.msg}.",
                    Location(file=file_name, line=exc.lineno),
                    "Check for a missing comma, quote or bracket just before that point.",
                ),
            )
        # JSON allows tabs between tokens (never inside strings); YAML does not.
        return data, SourceMap(file_name, text.replace("\t", " ")), []
    try:
        data = load_yaml_refusing_duplicates(text)
    except DuplicateKeyError as exc:
        return _duplicate_key(file_name, exc)
    except NumberTooLongError as exc:
        return _long_number(file_name, exc)
    except RecursionError:
        return _too_deep(file_name)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = mark.line + 1 if mark is not None else None
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        return _unreadable(
            file_name,
            error(
                "syntax_error",
                f"The YAML is malformed{f' at line {line}' if line else ''}: {problem}.",
                Location(file=file_name, line=line),
                "Check the indentation, and put labels containing ':' or '#' in quotes.",
            ),
        )
    return data, SourceMap(file_name, text), []


def read_document(path: Path) -> tuple[object, SourceMap, list[Diagnostic]]:
    """Read and parse a YAML/JSON file; problems come back as diagnostics, never raised."""
    name = str(path)
    where = Location(file=name)
    try:
        size = path.stat().st_size
        if size > MAX_DOCUMENT_BYTES:
            message = f"{name} is {size} bytes; the limit is {MAX_DOCUMENT_BYTES} bytes."
            return _unreadable(name, error("file_too_large", message, where))
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return _unreadable(name, error("file_not_found", f"There is no file {name}.", where))
    except IsADirectoryError:
        return _unreadable(name, error("file_not_found", f"{name} is a folder, not a file.", where))
    except UnicodeDecodeError as exc:
        return _unreadable(name, error("syntax_error", f"{name} is not UTF-8 text (byte {exc.start}).", where))
    except OSError as exc:
        return _unreadable(name, error("file_not_readable", f"{name} cannot be read: {exc.strerror}.", where))
    return parse_text(text, name)
