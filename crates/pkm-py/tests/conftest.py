"""Shared fixtures: the repository's example machines and the `pkm` command to
compare against (PKM_BIN, else target/debug/pkm or target/release/pkm)."""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples" / "machines"


def example(name):
    return str(EXAMPLES / name)


def all_examples():
    return sorted(str(p) for p in EXAMPLES.glob("*.toml"))


def pkm_bin():
    env = os.environ.get("PKM_BIN")
    if env:
        return env
    for profile in ("debug", "release"):
        p = ROOT / "target" / profile / "pkm"
        if p.exists():
            return str(p)
    pytest.fail("the pkm command is not built: run `cargo build -p pkm-cli` or set PKM_BIN")


def cli(*args, out=None):
    """Runs the pkm command, returns its parsed JSON stdout."""
    cmd = [pkm_bin(), *args]
    r = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if r.returncode not in (0, 3):
        raise AssertionError(f"{' '.join(cmd)} exited {r.returncode}: {r.stderr}")
    try:
        return json.loads(r.stdout)
    except json.JSONDecodeError:
        return None
