"""Finding the nerfpt binary, checking its version and reading what it prints.

Pure Python (no bpy), so that the tests can check it without Blender. nerfpt prints results on stdout and
everything else on stderr as lines: 'nerfpt: error: ...' (one line, then exit code 1), 'nerfpt: warning: ...',
'nerfpt: info: ...', and, when stderr is not a terminal, progress lines such as 'render: 40% (1.2M samples/s,
ETA 12 s)' (at most every 10% and every 2 s).
"""

import os
import re
import shutil
import subprocess

# The oldest nerfpt this add-on works with: `bake --backend`, `render --camera/--seed/--threads`, `info`.
MIN_VERSION = (0, 1, 0)

_VERSION_RE = re.compile(r"^nerfpt (\d+)\.(\d+)\.(\d+)\b")
_PROGRESS_RE = re.compile(r"^(render|bake): (\d+)%")
_ERROR_PREFIX = "nerfpt: error: "
_WARNING_PREFIX = "nerfpt: warning: "


class NerfptError(Exception):
    """A failure with a one-line message a user can act on (shown in Blender as one report)."""


def version_text(version):
    return ".".join(str(v) for v in version)


def parse_version(text):
    """(major, minor, patch) from `nerfpt --version` output, or None."""
    m = _VERSION_RE.match(text.strip())
    return tuple(int(g) for g in m.groups()) if m else None


def candidate_paths(configured, build_dirs=()):
    """Where to look for the binary, in order: the preference, PATH, the build folders the package recorded."""
    if configured:
        return [os.path.abspath(os.path.expanduser(configured))]
    found = []
    on_path = shutil.which("nerfpt")
    if on_path:
        found.append(on_path)
    for d in build_dirs:
        found.append(os.path.join(d, "nerfpt"))
    return found


def find_binary(configured, build_dirs=()):
    """The first candidate that is an executable file; raises NerfptError naming every place looked at."""
    candidates = candidate_paths(configured, build_dirs)
    for path in candidates:
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    if configured:
        path = candidates[0]
        if not os.path.exists(path):
            raise NerfptError(
                f"nerfpt binary '{path}' does not exist (set it in Preferences > Add-ons > nerfpt)"
            )
        raise NerfptError(f"nerfpt binary '{path}' is not an executable file")
    looked = ["PATH"] + [os.path.join(d, "nerfpt") for d in build_dirs]
    raise NerfptError(
        "nerfpt binary not found (looked on " + ", ".join(looked) + "): build nerfpt and set its path in "
        "Preferences > Add-ons > nerfpt"
    )


def check_version(path, timeout=20.0):
    """Runs `path --version`; returns the version tuple or raises NerfptError (missing, broken, too old)."""
    try:
        out = subprocess.run(
            [path, "--version"], capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL
        )
    except FileNotFoundError:
        raise NerfptError(f"nerfpt binary '{path}' does not exist") from None
    except PermissionError:
        raise NerfptError(f"nerfpt binary '{path}' cannot be run (permission denied)") from None
    except OSError as e:
        raise NerfptError(f"nerfpt binary '{path}' cannot be run: {e.strerror or e}") from None
    except subprocess.TimeoutExpired:
        raise NerfptError(f"'{path} --version' did not answer within {timeout:g} s") from None
    text = (out.stdout or "").strip() or (out.stderr or "").strip()
    version = parse_version(text) if out.returncode == 0 else None
    if version is None:
        first = text.splitlines()[0][:120] if text else "nothing"
        raise NerfptError(
            f"'{path} --version' printed '{first}' (exit code {out.returncode}): not a nerfpt binary"
        )
    if version < MIN_VERSION:
        raise NerfptError(
            f"nerfpt {version_text(version)} at '{path}' is too old: this add-on needs nerfpt "
            f"{version_text(MIN_VERSION)} or newer (rebuild it)"
        )
    return version


def progress_fraction(line):
    """0..1 from a progress line ('render: 40% ...', 'bake: 40% ...'), else None."""
    m = _PROGRESS_RE.match(line)
    return int(m.group(2)) / 100.0 if m else None


def error_message(line):
    """The message of a 'nerfpt: error: ...' line, else None."""
    return line[len(_ERROR_PREFIX) :].strip() if line.startswith(_ERROR_PREFIX) else None


def warning_message(line):
    """The message of a 'nerfpt: warning: ...' line, else None."""
    return line[len(_WARNING_PREFIX) :].strip() if line.startswith(_WARNING_PREFIX) else None


def failure_message(stderr_lines, returncode):
    """One line saying why a nerfpt run failed: its own error line, else its last words, else the exit code."""
    for line in reversed(stderr_lines):
        msg = error_message(line)
        if msg:
            return msg
    if returncode is not None and returncode < 0:
        return f"nerfpt was killed by signal {-returncode}"
    last = [ln.strip() for ln in stderr_lines if ln.strip() and progress_fraction(ln) is None]
    if last:
        return last[-1][:300]
    return f"nerfpt exited with code {returncode}"


def ignored_report(notes, nerfpt_warnings=(), scene_file=None):
    """The one warning of an export or a render: what the add-on found nerfpt does not render as Blender does
    (notes), then nerfpt's own warnings about the scene (its temporary file called 'scene'), each listed once in
    the order found. None when there is nothing to say."""
    items = list(notes)
    for w in nerfpt_warnings:
        if scene_file:
            w = w.replace(scene_file + ": ", "scene: ")
        items.append("nerfpt: " + w)
    unique = list(dict.fromkeys(items))
    return "nerfpt ignores: " + "; ".join(unique) if unique else None
