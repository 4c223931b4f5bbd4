#!/usr/bin/env python3
"""Copy a lahar case file with some keys changed: the one way the tools make a variant of a case
(a coarser dx, a shorter run, another kernel) without editing the original.

usage: case_override.py CASE OUT.yaml [PATH=VALUE ...]

PATH is a dotted key path into the case, VALUE is parsed as YAML:
    sph.dx=0.01   time.end=0.4   sph.kernel=wendland2   sph.blocks.0.box.hi=[0.1,0.2]
    bodies.cylinder.radius=0.03      (a list element by its `name:`, or by its index: bodies.0)
    bodies.gate={shape: box, ...}    (a map for a name the list does not have adds that element)
    materials.rock.kn=1e8            (a missing map key is added)
    sph.delta=~                      (~ or null removes the key: the loader's default applies)
Relative `file:` paths (STL blocks and bodies, terrain), `hydrograph:` and `level_hydrograph:` paths (inlets)
and `between: {top: FILE}` paths (terrain regions) are made absolute, so the copy may live anywhere.
The copy starts with a comment naming the original and the overrides; everything else (the check:
bounds included) is the original's. Comments and YAML anchors of the original are not kept (the
anchors are expanded). Exit status 0, or 2 with a message naming the path that cannot be applied.
The module's override_case() does the same from Python (tools/bench.py)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("yaml")
import yaml  # noqa: E402


class OverrideError(Exception):
    pass


class _NoAliasDumper(yaml.SafeDumper):
    """Writes every shared node in full: a case never needs anchors, and expanded copies can be
    changed one at a time."""

    def ignore_aliases(self, data):
        return True


def _plain(node):
    """Deep copy that breaks the sharing YAML aliases create (changing one use of an anchor must
    not change the others)."""
    if isinstance(node, dict):
        return {k: _plain(v) for k, v in node.items()}
    if isinstance(node, list):
        return [_plain(v) for v in node]
    return node


def parse_value(text):
    """A command-line value as YAML ('0.01' -> float, '[1, 2]' -> list, 'cubic' -> str)."""
    try:
        return yaml.safe_load(text) if text.strip() else ""
    except yaml.YAMLError as e:
        raise OverrideError(f"value {text!r} is not valid YAML: {e}")


def _child(node, key, path, create):
    """The element `key` of a map or list; `create` adds a missing map key (as a map)."""
    if isinstance(node, dict):
        if key not in node:
            if not create:
                raise OverrideError(f"{path}: no key '{key}'")
            node[key] = {}
        return node[key]
    if isinstance(node, list):
        return node[_list_index(node, key, path)]
    raise OverrideError(f"{path}: '{key}' is inside a {type(node).__name__}, not a map or list")


def _list_index(node, key, path):
    """A list element by index (0, -1) or by the value of its `name:` key."""
    try:
        i = int(key)
        if -len(node) <= i < len(node):
            return i
        raise OverrideError(f"{path}: index {i} out of range (the list has {len(node)} elements)")
    except ValueError:
        pass
    for i, el in enumerate(node):
        if isinstance(el, dict) and el.get("name") == key:
            return i
    names = [el.get("name") for el in node if isinstance(el, dict) and "name" in el]
    raise OverrideError(f"{path}: no element named '{key}' (names: {', '.join(map(str, names)) or 'none'})")


def _is_new_named_element(node, key, value):
    """`bodies.gate={...}` with no element named gate adds one: a map value, a key that is not an
    index, in a list of named maps."""
    try:
        int(key)
        return False
    except ValueError:
        pass
    return (isinstance(value, dict) and value.get("name", key) == key and
            all(isinstance(el, dict) and "name" in el for el in node))


def set_path(doc, path, value):
    """Set (or with value None remove) the key at dotted `path` in the loaded case `doc`."""
    keys = path.split(".")
    if not path or any(k == "" for k in keys):
        raise OverrideError(f"'{path}': empty key in the path")
    node = doc
    for depth, k in enumerate(keys[:-1]):
        node = _child(node, k, ".".join(keys[: depth + 1]), create=value is not None)
    last = keys[-1]
    if isinstance(node, dict):
        if value is None:
            node.pop(last, None)
        else:
            node[last] = value
    elif isinstance(node, list):
        try:
            i = _list_index(node, last, path)
        except OverrideError:
            if not _is_new_named_element(node, last, value):
                raise
            node.append({"name": last, **value})  # a body, block or probe the original does not have
            return
        if value is None:
            del node[i]
        else:
            node[i] = value
    else:
        raise OverrideError(f"{path}: the parent is a {type(node).__name__}, not a map or list")


def get_path(doc, path, default=None):
    """The value at dotted `path`, or `default` when a key on the way is missing."""
    node = doc
    try:
        for k in path.split("."):
            node = node[_list_index(node, k, path)] if isinstance(node, list) else node[k]
    except (KeyError, TypeError, OverrideError):
        return default
    return node


def _absolute_files(node, base):
    if isinstance(node, dict):
        for k, v in node.items():
            # `top:` of a between-region is a file when it is a string (2D: a CSV, 3D: an .asc)
            if k in ("file", "hydrograph", "level_hydrograph", "top") and isinstance(v, str) and not os.path.isabs(v):
                node[k] = os.path.normpath(os.path.join(base, v))
            else:
                _absolute_files(v, base)
    elif isinstance(node, list):
        for v in node:
            _absolute_files(v, base)


def load_case(path):
    with open(path) as f:
        doc = yaml.safe_load(f)
    if not isinstance(doc, dict):
        raise OverrideError(f"{path}: not a YAML map (a lahar case)")
    doc = _plain(doc)
    _absolute_files(doc, os.path.dirname(os.path.abspath(path)))
    return doc


def write_case(doc, out, comment=""):
    d = os.path.dirname(os.path.abspath(out))
    os.makedirs(d, exist_ok=True)
    with open(out, "w") as f:
        if comment:
            f.write("".join(f"# {line}\n" for line in comment.splitlines()))
        yaml.dump(doc, f, Dumper=_NoAliasDumper, sort_keys=False, default_flow_style=None, width=110)


def override_case(src, out, overrides):
    """Copy case `src` to `out` with `overrides` ({path: value} or [(path, value)]; a value None
    removes the key) applied. Returns the resulting document."""
    items = list(overrides.items()) if isinstance(overrides, dict) else list(overrides)
    doc = load_case(src)
    for path, value in items:
        set_path(doc, path, value)
    desc = " ".join(f"{p}={yaml.safe_dump(v, default_flow_style=True, width=1000).strip()}"
                    .replace("\n...", "") for p, v in items)
    write_case(doc, out, f"from {os.path.abspath(src)} by tools/case_override.py:{' ' + desc if desc else ''}")
    return doc


def main(argv):
    if len(argv) >= 2 and argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0
    if len(argv) < 3:
        sys.stderr.write("usage: case_override.py CASE OUT.yaml [PATH=VALUE ...]\n")
        return 2
    try:
        items = []
        for kv in argv[3:]:
            if "=" not in kv:
                raise OverrideError(f"'{kv}': expected PATH=VALUE (e.g. sph.dx=0.01)")
            path, text = kv.split("=", 1)
            items.append((path.strip(), parse_value(text)))
        override_case(argv[1], argv[2], items)
    except (OverrideError, OSError, yaml.YAMLError) as e:
        sys.stderr.write(f"case_override: {argv[1]}: {e}\n")
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
