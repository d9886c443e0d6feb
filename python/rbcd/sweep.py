"""rbcd-sweep: design-space sweeps of rbcd-sim, on local workers or a SLURM cluster.

    rbcd-sweep run    SWEEP.toml -o OUT [-j N]      run every point locally, resume what is missing
    rbcd-sweep list   SWEEP.toml                    validate and print the runs (nothing runs)
    rbcd-sweep slurm  SWEEP.toml -o OUT [--wait]    submit as a job array plus a dependent merge job
    rbcd-sweep status OUT                           progress of OUT (and its SLURM jobs, from squeue)
    rbcd-sweep merge  OUT                           assemble OUT/results.csv from the finished runs

The sweep file and the output directory are described in docs/sweeps.md.
Exit status: 0 every run succeeded; 1 some run failed (each one is recorded
in results.csv with its error) or a tool failed; 2 bad sweep file or command
line (one line on stderr, nothing written).
Standard library only (Python 3.11 for tomllib).
"""
import argparse
import concurrent.futures
import csv
import hashlib
import io
import itertools
import json
import math
import os
import re
import shlex
import shutil
import signal
import stat
import subprocess
import sys
import threading
import time
import tomllib

from rbcd.cli import (ArgumentParser, Once, UsageError, ascii_int, check_standard_output, escape, finite_float,
                      main_wrapper, open_trace, parse_toml, read_input_text, say, trace_errors, write_output)
from rbcd.startup import kept

PROG = "rbcd-sweep"
# Where the package is: REPO/python/rbcd in the source tree, P/share/rbcd/python/rbcd
# installed (`cmake --install`, programs in P/bin). Its parent goes on PYTHONPATH of
# the commands a SLURM job runs (rbcd-sweep task, merge).
PACKAGE_PARENT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The source tree's root, or installed P/share/rbcd: the default scene's source
# (scene/default_scene.toml, its frame count for [split]) is found under it.
DATA = os.path.dirname(PACKAGE_PARENT)
INSTALLED = os.path.basename(DATA) == "rbcd" and os.path.basename(os.path.dirname(DATA)) == "share"
# rbcd-sim unless --rbcd-sim, [sweep] rbcd_sim or $RBCD_SIM says: the build's in the
# source tree, installed the one in P/bin (beside the rbcd-sweep launcher).
DEFAULT_SIM = (os.path.join(os.path.dirname(os.path.dirname(DATA)), "bin", "rbcd-sim") if INSTALLED
               else os.path.join(DATA, "build", "bin", "rbcd-sim"))
DEFAULT_SIM_HELP = "rbcd-sim beside rbcd-sweep" if INSTALLED else "build/bin/rbcd-sim"
PLAN_FORMAT = "rbcd-sweep-plan 1"
RESULT_FORMAT = "rbcd-sweep-run 1"

DEFAULT_FIELDS = ["totals.frames", "totals.tiles", "totals.fragments", "totals.overflows",
                  "totals.stack_overflows", "totals.orphan_back_faces", "totals.hits", "totals.cycles",
                  "gpu.overhead_pct", "energy.total_nj"]


# The stats document's sections and, where flat, their keys (docs/stats.md): a
# results.fields entry outside them is most likely a typo, caught by `list`
# before any run (a warning, since a newer rbcd-sim may add keys).
STATS_KEYS = {"format": None, "input": None, "config": {}, "blocks": {}, "derived": {}, "energy": {},
              "provenance": {}, "frame_range": {"first", "last"},
              "time": {"clock_mhz", "fragments_per_second", "period_ps", "simulated_us", "wall_seconds"},
              "totals": {"cycles", "fragments", "frames", "hits", "orphan_back_faces", "overflows",
                         "stack_overflows", "tiles"},
              "gpu": {"bank_wait", "baseline_cycles", "culled_fragments", "culled_primitives", "cycles_with_unit",
                      "model", "overhead_cycles", "overhead_pct", "per_frame_overhead_pct", "primitives",
                      "shaded_fragments", "stalls", "tiles", "tiles_with_base"}}


def unknown_field(field):
    parts = field.split(".")
    if parts[0] not in STATS_KEYS:
        return True
    keys = STATS_KEYS[parts[0]]
    return keys is None and len(parts) > 1 or bool(keys) and len(parts) > 1 and parts[1] not in keys


class SweepError(UsageError):
    """Bad sweep file or command line: one line, exit 2."""


# A sweep file is a page of TOML; a larger one is refused before it is parsed.
MAX_SWEEP_BYTES = 4 << 20
# Runs a sweep may expand to unless --max-runs raises it: checked from the
# lists' lengths before any run is built (docs/limits.md).
DEFAULT_MAX_RUNS = 100000



# ---------------------------------------------------------------- small helpers

def toml_value(v, where):
    """A Python value from the sweep file as the TOML text rbcd-sim's --set takes."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)   # a TOML basic string
    raise SweepError(f"{where}: values must be integers, floats, booleans or strings, got {type(v).__name__}")


def cell(v):
    """A value as a CSV cell: the same text for the same value, whatever the run."""
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def flatten(table, prefix="", where=None, out=None):
    """{"zeb": {"banks": 2}} -> {"zeb.banks": 2}: dotted keys, quoted or nested, are the same
    key, so one given both ways ("zeb.banks" = [...] and zeb.banks = [...]) is given twice:
    refused naming `where` (a SweepError) rather than one silently dropped."""
    out = {} if out is None else out
    for k, v in table.items():
        key = prefix + k
        if isinstance(v, dict):
            flatten(v, key + ".", where, out)
        else:
            if key in out:
                raise SweepError(f"{where or 'sweep file'}: {key}: given twice (quoted and dotted keys name the same key)")
            out[key] = v
    return out


def write_atomic(path, text):
    """One of the sweep's own files in OUT, written whole through a temporary renamed
    over it (rbcd.cli.write_output): a reader never sees half a file, and whatever was
    planted at its name (a symlink, a hard link to an input, a FIFO) is replaced, never
    written through."""
    write_output(path, text, own=True)


def clear_outputs(*paths):
    """rbcd-sim's and rbcd-merge's outputs in a run's folder, removed before they run:
    a link planted at their names would be written through (those tools write
    through a symlink to a regular file, as documented), into a file that is none
    of the run's inputs they check against (the sweep file, a base configuration)."""
    for path in paths:
        if os.path.lexists(path) and not os.path.isdir(path):
            os.unlink(path)


def digest(obj):
    return hashlib.sha256(json.dumps(obj, sort_keys=True).encode()).hexdigest()[:16]


def lookup(stats, dotted):
    v = stats
    for part in dotted.split("."):
        if not isinstance(v, dict) or part not in v:
            return None
        v = v[part]
    return v if not isinstance(v, (dict, list)) else None


def one_line(text, prefix=None):
    """The message of a tool's stderr: its last line starting with `prefix` (rbcd-sim's own,
    not a sanitizer's remark), else the last line."""
    lines = [l.strip() for l in text.splitlines() if l.strip()]
    own = [l for l in lines if prefix and l.startswith(prefix)]
    return own[-1] if own else (lines[-1] if lines else "")


def count_frames(kind, path):
    """Frames of an input, for splitting it in frame ranges."""
    try:
        return _count_frames(kind, path)
    except tomllib.TOMLDecodeError as e:
        raise SweepError(f"{path}: {e}")
    except UsageError as e:   # (a key of too many dotted parts)
        raise SweepError(str(e)) from None
    except (OSError, EOFError) + trace_errors() as e:
        raise SweepError(f"{path}: cannot count its frames: {e}")


def _count_frames(kind, path):
    if kind == "default":
        path = os.path.join(DATA, "scene", "default_scene.toml")
        kind = "scene"
    if kind == "scene":
        with open(path, "rb") as f:
            text = f.read().decode()
        n = parse_toml(path, text).get("frames")
        if not isinstance(n, int) or n < 1:
            raise SweepError(f"{path}: frames: needs a positive integer to split the scene")
        return n
    n = 0
    with open_trace(path) as f:
        for line in f:
            s = line.lstrip()
            if s.startswith(b"frame") and s[5:6].isspace():
                n += 1
    return n


# ---------------------------------------------------------------- the sweep file

def not_a_file(path):
    """Why an input named as a file is not one: absent, or there but no
    regular file (a FIFO would block the sweep's frame count)."""
    return "not a regular file" if os.path.exists(path) else "no such file"


SWEEP_TABLES = {"sweep", "base", "axes", "zip", "inputs", "repeats", "results", "split", "slurm"}
SLURM_KEYS = {"partition": str, "time": str, "cpus_per_task": int, "runs_per_task": int,
              "max_parallel": int, "extra": list, "job_name": str}


class Sweep:
    """The sweep file, read and checked; expand() gives the runs."""

    def __init__(self, path, max_runs=DEFAULT_MAX_RUNS):
        self.path = path
        self.max_runs = max_runs
        self.dir = os.path.dirname(os.path.abspath(path))
        text = read_input_text(path, "sweep file", MAX_SWEEP_BYTES)
        try:
            self._read(path, text)
        except RecursionError:
            # Arrays, inline tables or dotted keys thousands deep: the parser (or
            # flatten) recurses once a level.
            raise SweepError(f"{path}: nested too deep to read (tables, arrays or dotted keys)")

    def _read(self, path, text):
        try:
            doc = parse_toml(path, text)
        except tomllib.TOMLDecodeError as e:
            raise SweepError(f"{path}: {e}")
        except UsageError as e:   # a key of more than 64 dotted parts (rbcd.cli)
            raise SweepError(str(e)) from None
        self.name = path
        for k in doc:
            if k not in SWEEP_TABLES:
                raise SweepError(f"{path}: {k}: unknown table (expected one of {', '.join(sorted(SWEEP_TABLES))})")
        get = lambda t, d=None: self._table(doc, t, d)
        self._read_base(get)
        seen = self._read_axes(get, doc)
        self._read_repeats(get, seen)

        self.inputs = self._inputs(get("inputs", {}))
        # The number of runs, from the lists' lengths, before anything is expanded.
        n = len(self.inputs) * len(self.seeds)
        for _, vals in self.dims:
            n *= len(vals)
        if n > self.max_runs:
            raise SweepError(f"{path}: {n} runs (axes x inputs x repeats), more than {self.max_runs} "
                             f"(the limit, raised by --max-runs; docs/limits.md)")
        self.input_sets = self._input_sets(get("inputs", {}).get("set", {}), seen)

        self._read_results(get)
        self._read_split(get)
        self._read_slurm(get)

    # -- the tables, each read and checked in the order above (the first error found is the one said)
    def _read_base(self, get):
        """[sweep] (which rbcd-sim) and [base] (its configuration under every point)."""
        path = self.path
        sweep = get("sweep", {})
        self._only(sweep, "sweep", {"rbcd_sim"})
        self.rbcd_sim = self._path(sweep["rbcd_sim"]) if "rbcd_sim" in sweep else None

        base = get("base", {})
        self._only(base, "base", {"config", "set"})
        self.base_config = self._path(base["config"], "base.config") if "config" in base else None
        if self.base_config and not os.path.isfile(self.base_config):
            raise SweepError(f"{path}: base.config: {base['config']}: {not_a_file(self.base_config)}")
        bset = base.get("set", {})
        if not isinstance(bset, dict):
            raise SweepError(f"{path}: base.set: must be a table of configuration keys")
        self.base_set = [(k, toml_value(v, f"{path}: base.set.{k}")) for k, v in flatten(bset, where=f"{path}: base.set").items()]

    def _read_axes(self, get, doc):
        """[axes] and [[zip]]: one grid dimension per key, one per [[zip]] group.
        Returns the swept keys, each with where it is swept."""
        path = self.path
        self.dims = []      # list of (keys, list of value tuples)
        seen = {}
        for k, vals in flatten(get("axes", {}), where=f"{path}: axes").items():
            self._check_values(f"axes.{k}", vals)
            self.dims.append(([k], [(v,) for v in vals]))
            seen[k] = f"axes.{k}"
        zips = doc.get("zip", [])
        if isinstance(zips, dict):
            zips = [zips]
        if not isinstance(zips, list) or not all(isinstance(z, dict) for z in zips):
            raise SweepError(f"{path}: zip: must be [[zip]] tables of key = [values]")
        for i, z in enumerate(zips):
            z = flatten(z, where=f"{path}: zip #{i + 1}")
            if not z:
                raise SweepError(f"{path}: zip #{i + 1}: empty")
            lens = set()
            for k, vals in z.items():
                self._check_values(f"zip #{i + 1}: {k}", vals)
                lens.add(len(vals))
                if k in seen:
                    raise SweepError(f"{path}: zip #{i + 1}: {k}: already swept by {seen[k]}")
                seen[k] = f"zip #{i + 1}"
            if len(lens) != 1:
                raise SweepError(f"{path}: zip #{i + 1}: lists of different lengths ({', '.join(f'{k}: {len(v)}' for k, v in z.items())})")
            keys = list(z)
            self.dims.append((keys, list(zip(*(z[k] for k in keys)))))
        self.axis_keys = [k for keys, _ in self.dims for k in keys]
        for keys, vals in self.dims:
            for t in vals:
                for k, v in zip(keys, t):
                    toml_value(v, f"{path}: axes: {k}")
        return seen

    def _read_repeats(self, get, seen):
        """[repeats]: the seeds each point runs with ([None]: rbcd-sim's own)."""
        path = self.path
        rep = get("repeats", {})
        self._only(rep, "repeats", {"count", "first_seed", "seeds"})
        if "seeds" in rep and ("count" in rep or "first_seed" in rep):
            raise SweepError(f"{path}: repeats: give seeds, or count and first_seed, not both")
        if "seeds" in rep:
            self._check_values("repeats.seeds", rep["seeds"])
            self.seeds = rep["seeds"]
        else:
            count = rep.get("count", 1)
            first = rep.get("first_seed", 1)
            if not isinstance(count, int) or isinstance(count, bool) or count < 1:
                raise SweepError(f"{path}: repeats.count: must be a positive integer")
            if count > self.max_runs:
                raise SweepError(f"{path}: repeats.count: {count} runs a point, more than {self.max_runs} "
                                 f"(the limit of runs, raised by --max-runs; docs/limits.md)")
            if not isinstance(first, int) or isinstance(first, bool) or first < 0:
                raise SweepError(f"{path}: repeats.first_seed: must be an unsigned integer")
            self.seeds = [first + r for r in range(count)] if (count > 1 or "first_seed" in rep) else [None]
        if any(not isinstance(s, int) or isinstance(s, bool) for s in self.seeds if s is not None):
            raise SweepError(f"{path}: repeats.seeds: must be integers")
        if self.seeds != [None] and "memory.seed" in seen:
            raise SweepError(f"{path}: repeats: memory.seed is already swept by {seen['memory.seed']}")

    def _read_results(self, get):
        """[results]: the stats fields in results.csv, and whether runs keep their collisions."""
        path = self.path
        res = get("results", {})
        self._only(res, "results", {"fields", "collisions"})
        self.fields = res.get("fields", DEFAULT_FIELDS)
        if not isinstance(self.fields, list) or not self.fields or not all(
                isinstance(f, str) and f and all(f.split(".")) for f in self.fields):
            raise SweepError(f"{path}: results.fields: must be a list of dotted stats paths (\"totals.hits\")")
        if len(set(self.fields)) != len(self.fields):
            raise SweepError(f"{path}: results.fields: a field is listed twice")
        self.keep_collisions = res.get("collisions", False)
        if not isinstance(self.keep_collisions, bool):
            raise SweepError(f"{path}: results.collisions: must be true or false")

    def _read_split(self, get):
        """[split]: each input in runs of frames_per_run frames (after [inputs]: not with inputs.frames)."""
        path = self.path
        split = get("split", {})
        self._only(split, "split", {"frames_per_run"})
        self.frames_per_run = split.get("frames_per_run")
        if self.frames_per_run is not None and (not isinstance(self.frames_per_run, int)
                                                 or isinstance(self.frames_per_run, bool)
                                                 or self.frames_per_run < 1):
            raise SweepError(f"{path}: split.frames_per_run: must be a positive integer")
        if self.frames_per_run is not None and self.frames is not None:
            raise SweepError(f"{path}: split.frames_per_run: cannot be combined with inputs.frames")

    def _read_slurm(self, get):
        """[slurm]: the submissions' options (rbcd-sweep slurm)."""
        path = self.path
        slurm = get("slurm", {})
        self._only(slurm, "slurm", set(SLURM_KEYS))
        for k, t in SLURM_KEYS.items():
            if k in slurm and (not isinstance(slurm[k], t) or isinstance(slurm[k], bool)):
                raise SweepError(f"{path}: slurm.{k}: must be {'a list of strings' if t is list else t.__name__}")
        if not all(isinstance(x, str) for x in slurm.get("extra", [])):
            raise SweepError(f"{path}: slurm.extra: must be a list of strings")
        for k in ("cpus_per_task", "runs_per_task", "max_parallel"):
            if slurm.get(k, 1) < 1:
                raise SweepError(f"{path}: slurm.{k}: must be at least 1")
        self.slurm = slurm

    # -- helpers of the reader
    def _table(self, doc, name, default):
        t = doc.get(name, default)
        if not isinstance(t, dict):
            raise SweepError(f"{self.path}: {name}: must be a table")
        return t

    def _only(self, table, name, allowed):
        for k in table:
            if k not in allowed:
                raise SweepError(f"{self.path}: {name}.{k}: unknown key (expected {', '.join(sorted(allowed))})")

    def _check_values(self, where, vals):
        if not isinstance(vals, list) or not vals:
            raise SweepError(f"{self.path}: {where}: must be a non-empty list of values")
        texts = [toml_value(v, f"{self.path}: {where}") for v in vals]
        if len(set(texts)) != len(texts):
            raise SweepError(f"{self.path}: {where}: a value is listed twice")

    def _path(self, p, where="path"):
        if not isinstance(p, str) or not p:
            raise SweepError(f"{self.path}: {where}: must be a path string")
        return os.path.normpath(os.path.join(self.dir, p))

    def _inputs(self, t):
        self._only(t, "inputs", {"default", "traces", "scenes", "suites", "set", "frames"})
        self.frames = t.pop("frames", None) if t else None
        if self.frames is not None and (not isinstance(self.frames, str)
                                        or not re.fullmatch(r"\d+(:\d*)?", self.frames)
                                        or (":" in self.frames and self.frames.split(":")[1]
                                            and int(self.frames.split(":")[1]) < int(self.frames.split(":")[0]))):
            raise SweepError(f"{self.path}: inputs.frames: must be \"A:B\" (A <= B), \"A:\" or \"A\", "
                             f"as rbcd-sim --frames")
        if self.frames is not None and any(x and int(x) >= 1 << 64 for x in self.frames.split(":")):
            raise SweepError(f"{self.path}: inputs.frames: a frame number beyond 2^64 - 1")
        out = []   # (label, kind, absolute path or None)
        if not {k for k in t if k != "set"}:
            t = {"default": True}
        d = t.get("default", False)
        if not isinstance(d, bool):
            raise SweepError(f"{self.path}: inputs.default: must be true or false")
        if d:
            out.append(("default", "default", None))
        for key, kind in (("traces", "trace"), ("scenes", "scene")):
            lst = t.get(key, [])
            if not isinstance(lst, list) or not all(isinstance(p, str) and p for p in lst):
                raise SweepError(f"{self.path}: inputs.{key}: must be a list of paths")
            for p in lst:
                full = self._path(p, f"inputs.{key}")
                if not os.path.isfile(full):
                    raise SweepError(f"{self.path}: inputs.{key}: {p}: {not_a_file(full)}")
                out.append((p, kind, full))
        suites = t.get("suites", [])
        if not isinstance(suites, list) or not all(isinstance(p, str) and p for p in suites):
            raise SweepError(f"{self.path}: inputs.suites: must be a list of folders")
        for s in suites:
            full = self._path(s, "inputs.suites")
            if not os.path.isdir(full):
                raise SweepError(f"{self.path}: inputs.suites: {s}: no such folder")
            members = []
            for name in sorted(os.listdir(full)):
                kind = ("scene" if name.endswith(".toml") else
                        "trace" if name.endswith((".rbt", ".rbt.gz", ".rbt.zst")) else None)
                if kind and os.path.isfile(os.path.join(full, name)):
                    members.append((os.path.join(s, name) if not s.endswith("/") else s + name,
                                    kind, os.path.join(full, name)))
            if not members:
                raise SweepError(f"{self.path}: inputs.suites: {s}: no scenes (*.toml) or traces (*.rbt, *.rbt.gz, *.rbt.zst)")
            out.extend(members)
        if not out:
            raise SweepError(f"{self.path}: inputs: no input (default = true, traces, scenes or suites)")
        labels = [l for l, _, _ in out]
        dup = {l for l in labels if labels.count(l) > 1}
        if dup:
            raise SweepError(f"{self.path}: inputs: {sorted(dup)[0]}: listed twice")
        return out

    def _input_sets(self, t, swept):
        """[inputs.set]: input name -> keys that input alone runs with (a scene whose ids
        need more zeb.id_bits, a trace with another tile size)."""
        if not isinstance(t, dict):
            raise SweepError(f"{self.path}: inputs.set: must be a table of input name = {{ key = value }}")
        labels = {l for l, _, _ in self.inputs}
        sets = {}
        for label, keys in t.items():
            where = f"{self.path}: inputs.set.\"{label}\""
            if label not in labels:
                raise SweepError(f"{where}: not an input of this sweep (inputs: {', '.join(sorted(labels))})")
            if not isinstance(keys, dict) or not keys:
                raise SweepError(f"{where}: must be a table of configuration keys")
            keys = flatten(keys, where=where)
            for k, v in keys.items():
                if k in swept:
                    raise SweepError(f"{where}: {k}: already swept by {swept[k]}")
                if k == "memory.seed" and self.seeds != [None]:
                    raise SweepError(f"{where}: memory.seed: already set by [repeats]")
            sets[label] = tuple((k, toml_value(v, f"{where}.{k}")) for k, v in keys.items())
        return sets

    def input_set(self, label):
        return self.input_sets.get(label, ())

    def read_files(self):
        """The files the sweep reads, (what, path): itself, its base
        configuration and its inputs (traces and scenes)."""
        return [("the sweep file", self.path)] + \
            ([("base.config", self.base_config)] if self.base_config else []) + \
            [(f"input {label}", full) for label, _, full in self.inputs if full]

    # -- expansion
    def points(self):
        """Every point of the grid, first axis slowest: list of [(key, value), ...]."""
        pts = []
        for combo in itertools.product(*(vals for _, vals in self.dims)):
            p = []
            for (keys, _), t in zip(self.dims, combo):
                p.extend(zip(keys, t))
            pts.append(p)
        return pts

    def sim_config_args(self, point, seed, input_set=()):
        args = []
        if self.base_config:
            args += ["--config", self.base_config]
        sets = list(self.base_set) + list(input_set) + [(k, toml_value(v, k)) for k, v in point]
        if seed is not None:
            sets.append(("memory.seed", str(seed)))
        for k, v in sets:
            args += ["--set", f"{k}={v}"]
        return args


# ---------------------------------------------------------------- planning

def find_rbcd_sim(cli_path, sweep):
    p = cli_path or (sweep.rbcd_sim if sweep else None) or os.environ.get("RBCD_SIM") or DEFAULT_SIM
    p = os.path.abspath(p)
    if not (os.path.isfile(p) and os.access(p, os.X_OK)):
        raise SweepError(f"rbcd-sim not found at {p} (build it, or give --rbcd-sim PATH)")
    return p


def config_checker(sim):
    """rbcd-config-check beside rbcd-sim (or $RBCD_CONFIG_CHECK; "none": check each point
    with rbcd-sim --dump-config instead, the same checks one process a point)."""
    p = os.environ.get("RBCD_CONFIG_CHECK")
    if p == "none":
        return None
    p = p or os.path.join(os.path.dirname(sim), "rbcd-config-check")
    return p if os.path.isfile(p) and os.access(p, os.X_OK) else None


def run_pool(jobs, workers, fn):
    """fn over jobs on `workers` threads; results in the order of jobs."""
    if workers <= 1 or len(jobs) <= 1:
        return [fn(j) for j in jobs]
    with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as ex:
        return list(ex.map(fn, jobs))


def validate(sweep, sim, workers, cache_path):
    """rbcd-sim --dump-config for every distinct point: its own checks, before anything runs.
    Returns the effective configuration's digest per (point, input set) (the runs' identity)."""
    pts = sweep.points()
    cache = {}
    if cache_path and os.path.isfile(cache_path):
        try:
            with open(cache_path, encoding="utf-8") as f:
                cache = json.load(f)
        except (OSError, ValueError):
            cache = {}
    base_digest = ""
    if sweep.base_config:
        with open(sweep.base_config, "rb") as f:
            base_digest = hashlib.sha256(f.read()).hexdigest()
    sim_stat = os.stat(sim)
    sim_id = f"{sim}:{sim_stat.st_size}:{sim_stat.st_mtime_ns}"

    # Point i with the first seed, once per distinct input set; the other seeds once each over the base.
    in_sets = list(dict.fromkeys(sweep.input_set(label) for label, _, _ in sweep.inputs))
    checks = [((i, s), sweep.sim_config_args(p, sweep.seeds[0], s)) for i, p in enumerate(pts) for s in in_sets]
    checks += [(None, sweep.sim_config_args([], s)) for s in sweep.seeds[1:]]

    def check(item):
        i, args = item
        key = digest([sim_id, base_digest, args])
        if key in cache:
            return i, args, key, 0, cache[key], ""
        r = subprocess.run([sim, "--dump-config"] + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           stdin=subprocess.DEVNULL)
        out = r.stdout.decode("utf-8", "replace")
        return i, args, key, r.returncode, hashlib.sha256(out.encode()).hexdigest()[:16], \
            one_line(r.stderr.decode("utf-8", "replace"), "rbcd-sim: ")

    checker = config_checker(sim)
    if checker:
        # The same checks and effective configuration, all points in one process.
        todo = [(i, args, digest([sim_id, base_digest, args])) for i, args in checks]
        ask = [t for t in todo if t[2] not in cache]
        answers = {}
        if ask:
            r = subprocess.run([checker], input="".join(json.dumps(a) + "\n" for _, a, _ in ask),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            lines = r.stdout.splitlines()
            if r.returncode != 0 or len(lines) != len(ask):
                raise RuntimeError(f"{checker} failed (status {r.returncode}): {one_line(r.stderr)}")
            for (_, _, key), line in zip(ask, lines):
                answers[key] = json.loads(line)
        results = []
        for i, args, key in todo:
            a = answers.get(key)
            if a is None:
                results.append((i, args, key, 0, cache[key], ""))
            elif a["status"] == 0:
                results.append((i, args, key, 0, hashlib.sha256(a["config"].encode()).hexdigest()[:16], ""))
            else:
                results.append((i, args, key, a["status"], "", "rbcd-sim: " + a["error"]))
    else:
        results = run_pool(checks, workers, check)
    digests = {}
    for i, args, key, rc, dig, err in results:
        if rc != 0:
            err = err.removeprefix("rbcd-sim: ")
            if i is None:
                raise SweepError(f"{sweep.path}: repeats: {err}" if rc == 2 else
                                 f"rbcd-sim --dump-config failed (status {rc}): {err}")
            i, s = i
            where = ", ".join(f"{k}={cell(v)}" for k, v in pts[i]) or "base"
            if s:
                where += "; input " + next(l for l, _, _ in sweep.inputs if sweep.input_set(l) == s)
            if rc == 2:
                raise SweepError(f"{sweep.path}: point {i} ({where}): {err}")
            raise SweepError(f"rbcd-sim --dump-config failed at point {i} (status {rc}): {err}")
        cache[key] = dig
        if i is not None:
            digests[i] = dig
    return digests, cache


def make_plan(sweep, sim, digests):
    """The runs: point x input x repeat (x frame range). Each run's id is a digest of
    what decides its result, so a resumed or edited sweep finds its finished runs."""
    pts = sweep.points()
    frames = {}
    if sweep.frames_per_run:
        for label, kind, path in sweep.inputs:
            frames[label] = count_frames(kind, path)
        n = len(pts) * len(sweep.seeds) * sum(max(1, -(-frames[l] // sweep.frames_per_run)) for l, _, _ in sweep.inputs)
        if n > sweep.max_runs:
            raise SweepError(f"{sweep.path}: split.frames_per_run: {n} runs, more than {sweep.max_runs} "
                             f"(the limit, raised by --max-runs; docs/limits.md)")
    runs, rows, seen_runs = [], [], set()
    for pi, p in enumerate(pts):
        for ii, (label, kind, path) in enumerate(sweep.inputs):
            for ri, seed in enumerate(sweep.seeds):
                base_args = sweep.sim_config_args(p, seed, sweep.input_set(label))
                in_args = [] if kind == "default" else (["--trace", path] if kind == "trace" else ["--scene", path])
                ident = {"config": digests[(pi, sweep.input_set(label))], "seed": seed, "input": [kind, label]}
                if sweep.frames is not None:
                    ident["frames_window"] = sweep.frames
                    in_args = in_args + ["--frames", sweep.frames]
                # A split row's merged outputs get a directory of their own, never a whole run's.
                row = {"id": digest(dict(ident, split=sweep.frames_per_run)) if sweep.frames_per_run else digest(ident), "point": pi, "input": label, "repeat": ri, "seed": seed,
                       "axes": [[k, cell(v)] for k, v in p], "parts": []}
                ranges = [None]
                if sweep.frames_per_run:
                    n, k = frames[label], sweep.frames_per_run
                    ranges = [(a, min(a + k, n) - 1) for a in range(0, n, k)] or [(0, 0)]
                for fr in ranges:
                    rid = digest(dict(ident, frames=fr)) if fr else row["id"]
                    # The last range open-ended ("A:"): rbcd-merge then knows the parts reach
                    # the input's end, and records the merged run as the whole input's.
                    last = fr is not None and fr == ranges[-1]
                    args = base_args + in_args + (["--frames", f"{fr[0]}:" if last else f"{fr[0]}:{fr[1]}"] if fr else [])
                    # Two points spelled apart with one effective configuration (400 and 400.0)
                    # are one run: its directory must not be written by two processes.
                    if rid not in seen_runs:
                        seen_runs.add(rid)
                        runs.append({"id": rid, "args": args, "frames": list(fr) if fr else None,
                                     "collisions": bool(sweep.keep_collisions or fr)})
                    row["parts"].append(rid)
                rows.append(row)
    return {"format": PLAN_FORMAT, "sweep": os.path.abspath(sweep.path), "rbcd_sim": sim,
            "axes": sweep.axis_keys, "seeds": sweep.seeds != [None], "fields": sweep.fields,
            "split": bool(sweep.frames_per_run), "inputs": [label for label, _, _ in sweep.inputs],
            "runs": runs, "rows": rows}


def load_plan(out):
    path = os.path.join(out, "plan.json")
    try:
        with open(path, encoding="utf-8") as f:
            plan = json.load(f)
    except OSError:
        raise SweepError(f"{out}: not a sweep output directory (no plan.json)")
    except ValueError as e:
        raise SweepError(f"{path}: {e}")
    if plan.get("format") != PLAN_FORMAT:
        raise SweepError(f"{path}: not a {PLAN_FORMAT} file")
    return plan


def read_result(out, rid):
    try:
        with open(os.path.join(out, "runs", rid, "result.json"), encoding="utf-8") as f:
            r = json.load(f)
        return r if r.get("format") == RESULT_FORMAT else None
    except (OSError, ValueError):
        return None


def pending_runs(out, plan):
    """Runs not complete: no result.json with status 0, or no collisions file where this plan
    keeps it (a run made by a sweep without results.collisions, into the same directory)."""
    return [r for r in plan["runs"] if (read_result(out, r["id"]) or {}).get("status") != 0
            or (r["collisions"] and not os.path.isfile(os.path.join(out, "runs", r["id"], "collisions.txt")))]


# ---------------------------------------------------------------- running

class Runner:
    """Runs rbcd-sim processes; SIGINT/SIGTERM stop them all, finished runs stay."""

    def __init__(self, jobs_per_run=1):
        self.lock = threading.Lock()
        self.procs = set()
        self.stopping = False
        self.jobs_per_run = jobs_per_run

    def stop(self, signum, _frame):
        with self.lock:
            self.stopping = True
            for p in self.procs:
                try:
                    p.send_signal(signal.SIGTERM)
                except OSError:
                    pass
        raise KeyboardInterrupt

    def run_one(self, out, sim, run):
        """One run into OUT/runs/ID/: rbcd-sim's stats JSON (and collisions), its stderr
        when it printed anything (stderr.txt: warnings are kept, docs/sweeps.md), then
        result.json last and atomically: its presence with status 0 means done."""
        d = os.path.join(out, "runs", run["id"])
        with self.lock:
            if self.stopping:
                return None
        created = not os.path.isdir(d)
        os.makedirs(d, exist_ok=True)
        # One thread a run: the sweep's parallelism is its workers, and a run's
        # own second thread would only compete with them (docs/sweeps.md, "Speed").
        clear_outputs(os.path.join(d, "stats.json"), os.path.join(d, "collisions.txt"))
        cmd = [sim, "-q", "--threads", "1", "--stats", os.path.join(d, "stats.json")] + run["args"]
        if self.jobs_per_run > 1 and splits_well(run["args"]):
            cmd += ["--jobs", str(self.jobs_per_run)]
        if run["collisions"]:
            cmd += ["--collisions", os.path.join(d, "collisions.txt")]
        t0 = time.monotonic()
        with self.lock:
            if self.stopping:
                # Interrupted since the check above, maybe after the folder
                # was made: a folder this run created goes, as below.
                if created:
                    shutil.rmtree(d, ignore_errors=True)
                return None
            try:
                p = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.PIPE)
            except OSError:
                # rbcd-sim could not be started (gone, no longer executable, out
                # of processes or descriptors): the sweep stops with the error,
                # and a folder this run made, empty, goes as an interrupted one does.
                if created:
                    shutil.rmtree(d, ignore_errors=True)
                raise
            self.procs.add(p)
        try:
            _, err = p.communicate()
        finally:
            with self.lock:
                self.procs.discard(p)
        wall = time.monotonic() - t0
        with self.lock:
            if self.stopping:
                # Killed by us: not a result. A folder this run created holds at
                # most a partial output: removed, so that an interrupted sweep
                # leaves only finished runs (resume reruns the rest).
                if created and not os.path.exists(os.path.join(d, "result.json")):
                    shutil.rmtree(d, ignore_errors=True)
                return None
        rc = p.returncode
        err_text = err.decode("utf-8", "replace")
        warnings = [l for l in err_text.splitlines() if ": warning: " in l]
        stderr_path = os.path.join(d, "stderr.txt")
        if err_text:
            write_atomic(stderr_path, err_text)
        elif os.path.lexists(stderr_path):
            os.unlink(stderr_path)   # an earlier attempt's
        res = {"format": RESULT_FORMAT, "status": rc if rc >= 0 else f"signal {-rc}",
               "error": "" if rc == 0 else (one_line(err.decode("utf-8", "replace"), "rbcd-sim: ").removeprefix("rbcd-sim: ")
                                            or f"exit status {rc}"),
               "wall_s": round(wall, 6),
               "warnings": warnings,
               "command": " ".join(shlex.quote(c) for c in cmd)}
        write_atomic(os.path.join(d, "result.json"), json.dumps(res, indent=1) + "\n")
        return res


class Progress:
    def __init__(self, total, quiet):
        self.total, self.done, self.failed = total, 0, 0
        self.quiet = quiet
        self.t0 = time.monotonic()
        self.last = 0.0
        self.step = 0
        self.tty = sys.stderr.isatty()

    def line(self):
        el = time.monotonic() - self.t0
        rate = self.done / el if el > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else float("nan")
        eta = "?" if math.isnan(left) else time.strftime("%H:%M:%S", time.gmtime(left))
        return (f"{PROG}: {self.done}/{self.total} runs, {self.failed} failed, "
                f"{rate:.2f} runs/s, {eta} left")

    def tick(self, ok, final=False):
        if ok is not None:
            self.done += 1
            self.failed += 0 if ok else 1
        if self.quiet:
            return
        now = time.monotonic()
        if self.tty:
            if final or now - self.last > 0.2:
                sys.stderr.write("\r" + self.line() + ("\n" if final else "\033[K"))
                sys.stderr.flush()
                self.last = now
        else:
            # Not a terminal (a log): a line every 2 s, and at every tenth of the runs.
            step = self.done * 10 // max(1, self.total)
            if final or now - self.last >= 2 or step > self.step:
                sys.stderr.write(self.line() + "\n")
                sys.stderr.flush()
                self.last = now
                self.step = step


def splits_well(args):
    """Whether rbcd-sim --jobs speeds this run up: a scene, a plain or a zstd
    trace file. A gzip trace is inflated in one stream whatever the split
    (docs/performance.md, "One run on N cores"), and standard input cannot be split."""
    if "--trace" not in args:
        return True
    path = args[args.index("--trace") + 1]
    try:
        with open(path, "rb") as f:
            return path != "-" and f.read(2) != b"\x1f\x8b"
    except OSError:
        return False


def execute(out, plan, runs, workers, quiet, resume="rerun the same command to resume"):
    """Runs `runs` on `workers` local workers; True unless interrupted. Fewer runs
    than workers: the spare cores go to each run's frames (rbcd-sim --jobs), the
    same bytes as one process (docs/sweeps.md, "Speed")."""
    runner = Runner(workers // len(runs) if 0 < len(runs) < workers else 1)
    # SIGINT or SIGHUP ignored when the program started (a script's
    # background job, nohup) stays ignored.
    old = {s: signal.signal(s, runner.stop) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP) if kept(s)}
    prog = Progress(len(runs), quiet)
    prog.tick(None)
    ex = concurrent.futures.ThreadPoolExecutor(max_workers=max(1, workers))
    try:
        futs = [ex.submit(runner.run_one, out, plan["rbcd_sim"], r) for r in runs]
        for f in concurrent.futures.as_completed(futs):
            res = f.result()
            if res is not None:
                prog.tick(res["status"] == 0)
        prog.tick(None, final=True)
        return True
    except KeyboardInterrupt:
        ex.shutdown(wait=True, cancel_futures=True)
        sys.stderr.write(f"\n{PROG}: interrupted; {prog.done} runs finished are kept, {resume}\n")
        return False
    finally:
        ex.shutdown(wait=True, cancel_futures=True)
        for s, h in old.items():
            signal.signal(s, h)


# ---------------------------------------------------------------- assembling

def merge_parts(out, plan, parts, dest_dir):
    """A split row's frame ranges merged by rbcd-merge (beside rbcd-sim) into the
    stats JSON and collisions file one run over all the frames writes, byte for
    byte, wall time aside (docs/sweeps.md)."""
    merger = os.path.join(os.path.dirname(plan["rbcd_sim"]), "rbcd-merge")
    if not os.access(merger, os.X_OK):
        raise RuntimeError(f"rbcd-merge not found beside rbcd-sim ({merger})")
    os.makedirs(dest_dir, exist_ok=True)
    clear_outputs(os.path.join(dest_dir, "stats.json"), os.path.join(dest_dir, "collisions.txt"))
    r = subprocess.run([merger, "--stats", os.path.join(dest_dir, "stats.json"),
                        "--collisions", os.path.join(dest_dir, "collisions.txt")] +
                       [os.path.join(out, "runs", p, "stats.json") for p in parts],
                       stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    if r.returncode != 0:
        raise RuntimeError(one_line(r.stderr.decode("utf-8", "replace"), "rbcd-merge: ")
                           or f"rbcd-merge: exit status {r.returncode}")
    write_atomic(os.path.join(dest_dir, "merged_from.json"), json.dumps(parts) + "\n")


def assemble(out, plan, quiet=False):
    """OUT/results.csv (one row per point x input x repeat, sorted, deterministic) and
    OUT/wall.csv (wall times, which vary run to run). Returns (rows, failed, missing)."""
    results = {r["id"]: read_result(out, r["id"]) for r in plan["runs"]}
    frames_of = {r["id"]: r["frames"] for r in plan["runs"]}
    input_order = {label: i for i, label in enumerate(plan["inputs"])}
    fields = plan["fields"]
    head = ["point", "input", "repeat"] + (["memory.seed"] if plan["seeds"] else []) + plan["axes"] + \
        fields + ["status", "error", "run"]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(head)
    wbuf = io.StringIO()
    ww = csv.writer(wbuf, lineterminator="\n")
    ww.writerow(["run", "point", "input", "repeat", "frames", "wall_s"])
    failed = missing = 0
    seen_fields = set()
    ran = {}   # run id -> "A:B", the frames an unsplit run's stats say it ran
    for row in sorted(plan["rows"], key=lambda r: (r["point"], input_order[r["input"]], r["repeat"])):
        parts = row["parts"]
        res = [results[p] for p in parts]
        status, error, values = "", "not run", {}
        bad = next(((p, r) for p, r in zip(parts, res) if r is not None and r["status"] != 0), None)
        if bad:
            p, r = bad
            status, error = r["status"], r["error"]
            if plan["split"]:
                fr = frames_of[p]
                error = f"frames {fr[0]}:{fr[1]}: {error}"
        elif all(r is not None for r in res):
            status, error = 0, ""
            try:
                if plan["split"]:
                    merge_parts(out, plan, parts, os.path.join(out, "runs", row["id"]))
                with open(os.path.join(out, "runs", row["id"], "stats.json"), encoding="utf-8") as f:
                    stats = json.load(f)
                fr_ = stats.get("frame_range") if isinstance(stats, dict) else None
                if not plan["split"] and isinstance(fr_, dict) and {"first", "last"} <= fr_.keys():
                    ran[row["id"]] = f"{fr_['first']}:{fr_['last']}"
                for fld in fields:
                    values[fld] = lookup(stats, fld)
                    if values[fld] is not None:
                        seen_fields.add(fld)
            except (OSError, ValueError, KeyError, RuntimeError) as e:
                status, error = "merge", f"{type(e).__name__}: {e}"
        if status == "":
            missing += 1
        elif status != 0:
            failed += 1
        w.writerow([row["point"], row["input"], row["repeat"]] + ([cell(row["seed"])] if plan["seeds"] else []) +
                   [v for _, v in row["axes"]] + [cell(values.get(f)) for f in fields] + [status, error, row["id"]])
        for p, r in zip(parts, res):
            fr = frames_of[p]
            ww.writerow([p, row["point"], row["input"], row["repeat"], f"{fr[0]}:{fr[1]}" if fr else ran.get(p, ""),
                         "" if r is None else f"{r['wall_s']:.3f}"])
    write_atomic(os.path.join(out, "results.csv"), buf.getvalue())
    write_atomic(os.path.join(out, "wall.csv"), wbuf.getvalue())
    summarize_warnings(out, plan, results, quiet)
    if failed + missing < len(plan["rows"]):
        for fld in fields:
            if fld not in seen_fields:
                say(PROG, f"warning: results.fields: {fld}: in no run's stats JSON")
    return len(plan["rows"]), failed, missing


def summarize_warnings(out, plan, results, quiet):
    """rbcd-sim's warnings (mesh hygiene, ...) of every run, each distinct line once
    with the runs that printed it, in OUT/warnings.txt, and one line on stderr;
    each run's whole stderr stays in OUT/runs/ID/stderr.txt."""
    seen = {}
    for r in plan["runs"]:
        res = results.get(r["id"])
        for w in (res or {}).get("warnings", []):
            seen.setdefault(w, []).append(r["id"])
    path = os.path.join(out, "warnings.txt")
    if not seen:
        if os.path.isfile(path):
            os.unlink(path)
        return
    lines = [f"{len(ids)} runs ({' '.join(ids[:8])}{' ...' if len(ids) > 8 else ''}): {w}" for w, ids in seen.items()]
    write_atomic(path, "\n".join(lines) + "\n")
    runs = len({i for ids in seen.values() for i in ids})
    if not quiet:
        say(PROG, f"warning: {runs} runs printed {len(seen)} distinct rbcd-sim warnings ({path}); "
                  f"the first: {next(iter(seen))}")


# ---------------------------------------------------------------- commands

def prepare(args, workers):
    sweep = Sweep(args.sweep, args.max_runs)
    sim = find_rbcd_sim(args.rbcd_sim, sweep)
    check_standard_output(sweep.read_files() + [("rbcd-sim", sim)])
    cache_path = os.path.join(args.out, "validated.json") if getattr(args, "out", None) else None
    digests, cache = validate(sweep, sim, workers, cache_path)
    plan = make_plan(sweep, sim, digests)
    for fld in sweep.fields:
        if unknown_field(fld):
            say(PROG, f"warning: {sweep.path}: results.fields: {fld}: not a key of rbcd-sim's stats document "
                      f"(docs/stats.md); its column will stay empty")
    return sweep, plan, cache


def write_plan(out, plan, cache):
    os.makedirs(os.path.join(out, "runs"), exist_ok=True)
    write_atomic(os.path.join(out, "plan.json"), json.dumps(plan, indent=1) + "\n")
    write_atomic(os.path.join(out, "validated.json"), json.dumps(cache, indent=0, sort_keys=True) + "\n")


def cores():
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def lock_out(out):
    """One runner (or submitter) per output directory at a time; SLURM tasks need no lock
    since each writes only its own runs."""
    import fcntl
    os.makedirs(out, exist_ok=True)
    try:   # (not truncated, no link followed: a .lock planted onto an input is no lock)
        f = os.fdopen(os.open(os.path.join(out, ".lock"),
                              os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NOCTTY, 0o666), "r+b")
    except OSError as e:
        raise SweepError(f"-o {out}: .lock cannot be opened ({e.strerror}): not the sweep's own lock file")
    st = os.fstat(f.fileno())
    if st.st_nlink != 1 or not stat.S_ISREG(st.st_mode):
        f.close()
        raise SweepError(f"-o {out}: .lock is another name for a file, or not a regular file: not the sweep's own")
    try:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        raise SweepError(f"-o {out}: in use by another rbcd-sweep")
    lock_out.held = f   # held until the process exits


def check_out(out, sweep):
    """Before anything is written: OUT and what the sweep writes into it are what they
    must be (a dangling symlink, or a file where runs/ goes, is refused here, not after
    .lock and plan.json are written), and none of it is the sweep file."""
    if os.path.lexists(out) and not os.path.isdir(out):
        raise SweepError(f"-o {out}: exists and is not a directory")
    real, base = os.path.realpath(sweep), os.path.realpath(out) + os.sep
    written = [os.path.join(base, f) for f in ("plan.json", "validated.json", "results.csv", "wall.csv", ".lock")]
    if real in written or real.startswith((base + "runs" + os.sep, base + "slurm" + os.sep)):
        raise SweepError(f"-o {out}: the sweep writes {real}, the sweep file {sweep}")
    if os.path.isdir(out) and set(os.listdir(out)) - {".lock"} and not os.path.isfile(os.path.join(out, "plan.json")):
        raise SweepError(f"-o {out}: a non-empty directory that is not a sweep output")
    for d in ("runs", "slurm", os.path.join("slurm", "logs")):
        p = os.path.join(out, d)
        if os.path.lexists(p) and (not os.path.isdir(p) or os.path.islink(p)):
            raise SweepError(f"-o {out}: {d} exists and is not a directory of its own (a file, or a symbolic link)")
    runs = os.path.join(out, "runs")
    for rid in sorted(os.listdir(runs)) if os.path.isdir(runs) else ():
        if os.path.islink(os.path.join(runs, rid)):
            raise SweepError(f"-o {out}: runs/{rid} is a symbolic link, not a run's own folder")
    for f in ("plan.json", "validated.json", "results.csv", "wall.csv", ".lock"):
        p = os.path.join(out, f)
        if os.path.lexists(p) and not os.path.isfile(p):
            raise SweepError(f"-o {out}: {f} exists and is not a regular file")


def finish(out, plan, quiet):
    rows, failed, missing = assemble(out, plan, quiet)
    if not quiet or failed or missing:
        say(PROG, f"{out}/results.csv: {rows} rows, {failed} failed, {missing} not run")
    return 0 if failed == 0 and missing == 0 else 1


def cmd_run(args):
    check_out(args.out, args.sweep)
    workers = args.jobs or cores()
    tv = time.monotonic()
    _, plan, cache = prepare(args, workers)
    lock_out(args.out)
    write_plan(args.out, plan, cache)
    tv = time.monotonic() - tv
    todo = pending_runs(args.out, plan)
    if not args.quiet:
        sys.stderr.write(f"{PROG}: {len(plan['runs'])} runs, {len(plan['runs']) - len(todo)} already complete, "
                         f"{len(todo)} to run on {workers} workers\n")
    t0 = time.monotonic()
    ok = execute(args.out, plan, todo, workers, args.quiet or not todo)
    if not ok:
        return 130
    status = finish(args.out, plan, args.quiet)
    if args.timing:
        # Validation + planning, then running + assembling, against the runs' own wall times.
        walls = [(read_result(args.out, r["id"]) or {}).get("wall_s", 0.0) for r in todo]
        import resource
        me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
        print(json.dumps({"runs": len(todo), "workers": workers, "validate_s": round(tv, 3),
                          "run_s": round(time.monotonic() - t0, 3), "sum_run_wall_s": round(sum(walls), 3),
                          "runner_cpu_s": round(me.ru_utime + me.ru_stime, 3),
                          "children_cpu_s": round(kids.ru_utime + kids.ru_stime, 3)}))
    return status


def cmd_list(args):
    workers = args.jobs or cores()
    _, plan, _ = prepare(args, workers)
    byid = {r["id"]: r for r in plan["runs"]}
    for row in plan["rows"]:
        for p in row["parts"]:
            r = byid[p]
            fr = f"{r['frames'][0]}:{r['frames'][1]}" if r["frames"] else "-"
            print("\t".join([str(row["point"]), escape(row["input"]), str(row["repeat"]), fr,
                             escape(" ".join(shlex.quote(a) for a in r["args"]))]))
    return 0


def cmd_merge(args):
    plan = load_plan(args.out)
    return finish(args.out, plan, args.quiet)


# ---------------------------------------------------------------- SLURM

def slurm_tool(name, argv, what):
    try:
        r = subprocess.run([name] + argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    except FileNotFoundError:
        raise SweepError(f"{name}: not found (SLURM client commands are needed for {what})")
    return r


def sbatch(argv):
    r = slurm_tool("sbatch", ["--parsable"] + argv, "slurm")
    if r.returncode != 0:
        raise RuntimeError(f"sbatch failed: {one_line(r.stderr) or r.returncode}")
    return r.stdout.strip().split(";")[0]


def self_command(*argv):
    """rbcd-sweep as a SLURM job runs it (a task, the merge): this package, by
    /usr/bin/python3 -m, whatever the job's PYTHONPATH (set to the package's
    parent) and working directory (-P: not searched for modules)."""
    return ["env", f"PYTHONPATH={PACKAGE_PARENT}", "/usr/bin/python3", "-P", "-m", "rbcd.sweep", *argv]


def cmd_slurm(args):
    check_out(args.out, args.sweep)
    sweep, plan, cache = prepare(args, cores())
    out = os.path.abspath(args.out)
    lock_out(out)
    write_plan(out, plan, cache)
    todo = [r["id"] for r in pending_runs(out, plan)]
    cfg = sweep.slurm
    per = cfg.get("runs_per_task", 1)
    chunks = [todo[i:i + per] for i in range(0, len(todo), per)]
    sdir = os.path.join(out, "slurm")
    os.makedirs(os.path.join(sdir, "logs"), exist_ok=True)
    stamp = time.strftime("%Y%m%d-%H%M%S") + f"-{os.getpid()}"
    chunk_file = os.path.join(sdir, f"chunks-{stamp}.json")
    write_atomic(chunk_file, json.dumps(chunks) + "\n")
    common = [f"--job-name={cfg.get('job_name', 'rbcd-sweep')}"]
    if "partition" in cfg:
        common.append(f"--partition={cfg['partition']}")
    common += cfg.get("extra", [])
    jobs = {"submitted": stamp, "array": None, "merge": None, "tasks": len(chunks)}
    # Earlier submissions into this directory keep their ids (status, accounting).
    jobs_path = os.path.join(sdir, "jobs.json")
    earlier = []
    try:
        with open(jobs_path, encoding="utf-8") as f:
            prev = json.load(f)
        if isinstance(prev, dict):
            earlier = [e for e in prev.get("earlier", []) if isinstance(e, dict)]
            earlier.append({k: v for k, v in prev.items() if k != "earlier"})
    except (OSError, ValueError):
        pass
    jobs["earlier"] = earlier
    if chunks:
        array = f"0-{len(chunks) - 1}" + (f"%{cfg['max_parallel']}" if cfg.get("max_parallel") else "")
        task_argv = common + [f"--array={array}", f"--cpus-per-task={cfg.get('cpus_per_task', 1)}",
                              f"--output={sdir}/logs/%A_%a.out"]
        if "time" in cfg:
            task_argv.append(f"--time={cfg['time']}")
        jobs["array"] = sbatch(task_argv + ["--wrap", shlex.join(
            self_command("task", out, chunk_file)) + ' "$SLURM_ARRAY_TASK_ID"'])
    merge_argv = common + ["--ntasks=1", "--cpus-per-task=1", f"--output={sdir}/logs/merge-%j.out"]
    if jobs["array"]:
        merge_argv.append(f"--dependency=afterany:{jobs['array']}")
    jobs["merge"] = sbatch(merge_argv + ["--wrap", shlex.join(self_command("merge", "-q", out))])
    write_atomic(jobs_path, json.dumps(jobs, indent=1) + "\n")
    if not args.quiet:
        sys.stderr.write(f"{PROG}: {len(plan['runs'])} runs, {len(todo)} to run in {len(chunks)} array tasks"
                         + (f" (job {jobs['array']})" if jobs["array"] else "") + f", merge job {jobs['merge']}\n")
    if not args.wait:
        return 0
    last = ""
    while True:
        state = squeue_state([j for j in (jobs["array"], jobs["merge"]) if j])
        if state is None:
            time.sleep(args.poll)
            continue
        line = status_line(out, plan, state)
        if not args.quiet and line != last:
            sys.stderr.write(line + "\n")
            last = line
        if not state:
            break
        time.sleep(args.poll)
    rows, failed, missing = assemble(out, plan, args.quiet)   # what the merge job wrote, checked again here
    if not args.quiet or failed or missing:
        say(PROG, f"{out}/results.csv: {rows} rows, {failed} failed, {missing} not run")
    return 0 if failed == 0 and missing == 0 else 1


def squeue_state(job_ids):
    """{state: count} of the jobs' tasks still known to squeue."""
    if not job_ids:
        return {}
    r = slurm_tool("squeue", ["-h", "-r", "-j", ",".join(job_ids), "-o", "%T"], "status")
    if r.returncode != 0:
        if "invalid job id" in r.stderr.lower():
            return {}   # squeue forgets finished jobs: an unknown id is a finished one
        return None     # the controller did not answer: ask again later
    state = {}
    for line in r.stdout.split():
        state[line] = state.get(line, 0) + 1
    return state


def status_line(out, plan, state):
    done = failed = 0
    for r in plan["runs"]:
        res = read_result(out, r["id"])
        if res is not None:
            done += 1
            failed += res["status"] != 0
    jobs = ", ".join(f"{n} {s.lower()}" for s, n in sorted(state.items())) or "no jobs queued"
    return f"{PROG}: {done}/{len(plan['runs'])} runs done, {failed} failed; slurm: {jobs}"


def cmd_status(args):
    plan = load_plan(args.out)
    ids = []
    jf = os.path.join(args.out, "slurm", "jobs.json")
    if os.path.isfile(jf):
        with open(jf, encoding="utf-8") as f:
            j = json.load(f)
        ids = [x for x in (j.get("array"), j.get("merge")) if x]
    if not ids:
        print(status_line(args.out, plan, {}).split("; slurm:")[0])
        return 0
    state = squeue_state(ids)
    print(status_line(args.out, plan, state) if state is not None else
          status_line(args.out, plan, {}).replace("no jobs queued", "squeue did not answer"))
    return 0


def cmd_task(args):
    """One SLURM array task: its chunk of runs, on the CPUs SLURM gave it."""
    plan = load_plan(args.out)
    with open(args.chunks, encoding="utf-8") as f:
        chunks = json.load(f)
    ids = set(chunks[args.index])
    runs = [r for r in plan["runs"] if r["id"] in ids]
    workers = int(os.environ.get("SLURM_CPUS_PER_TASK", "1"))
    return 0 if execute(args.out, plan, runs, workers, quiet=True,
                        resume="submit the sweep again (rbcd-sweep slurm) to run the rest") else 130


# ---------------------------------------------------------------- main

def check_stdout(args):
    """Standard output (the listing, the status) opened by the shell onto
    the sweep file or a file of the output directory (1<>S.toml,
    1<>OUT/plan.json, or a hard link to one elsewhere) would be written
    into it: refused. (A SLURM task's and the merge job's standard output
    is a log file of OUT/slurm/logs, which nothing reads.) The sweep's
    other inputs are checked once it is read (prepare)."""
    if getattr(args, "sweep", None):
        check_standard_output([("the sweep file", args.sweep)])
    out = getattr(args, "out", None)
    if args.cmd == "task" or not out or not os.path.isdir(out):
        return
    try:
        st = os.fstat(1)
        target = os.path.realpath("/proc/self/fd/1")
    except OSError:
        return
    base = os.path.realpath(out) + os.sep
    if not stat.S_ISREG(st.st_mode) or (st.st_nlink == 1 and not target.startswith(base)):
        return   # (neither a file of OUT by its path nor, hard-linked elsewhere, by its inode)
    files = []
    for d, dirs, names in os.walk(base):
        dirs[:] = [n for n in dirs if os.path.join(d, n) != base + "slurm"]
        files += [os.path.join(d, n) for n in names]
    check_standard_output([("a file of the output directory", f) for f in files])


def run(argv):
    ap = ArgumentParser(prog=PROG, description=__doc__.split("\n")[0],
                formatter_class=argparse.RawDescriptionHelpFormatter, epilog="\n".join(__doc__.split("\n")[2:9]))
    sub = ap.add_subparsers(dest="cmd", required=True)

    def sweep_cmd(name, help_text, out):
        p = sub.add_parser(name, help=help_text)
        p.add_argument("sweep", help="sweep file (TOML, docs/sweeps.md)")
        if out:
            p.add_argument("-o", "--out", action=Once, required=True, help="output directory")
        p.add_argument("--rbcd-sim", action=Once,
                       help=f"rbcd-sim executable (default: $RBCD_SIM, else {DEFAULT_SIM_HELP})")
        p.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
        p.add_argument("--max-runs", action=Once, type=ascii_int, default=DEFAULT_MAX_RUNS,
                       help=f"refuse a sweep of more runs (default {DEFAULT_MAX_RUNS}; docs/limits.md)")
        return p

    p = sweep_cmd("run", "run the sweep on local workers", True)
    p.add_argument("-j", "--jobs", action=Once, type=ascii_int, default=0, help="workers (default: the cores)")
    p.add_argument("--timing", action="store_true", help="print elapsed and summed run wall time as JSON")
    p = sweep_cmd("list", "validate and print the runs", False)
    p.add_argument("-j", "--jobs", action=Once, type=ascii_int, default=0,
                   help="validation workers (default: the cores)")
    p = sweep_cmd("slurm", "submit the sweep to SLURM", True)
    p.add_argument("--wait", action="store_true", help="poll squeue until the merge job is done")
    p.add_argument("--poll", action=Once, type=finite_float, default=5.0,
                   help="seconds between squeue polls (default 5)")
    for name, h in (("status", "progress of an output directory"), ("merge", "assemble results.csv")):
        p = sub.add_parser(name, help=h)
        p.add_argument("out")
        p.add_argument("-q", "--quiet", action="store_true")
    p = sub.add_parser("task", help="(internal) one SLURM array task")
    p.add_argument("out")
    p.add_argument("chunks")
    p.add_argument("index", type=ascii_int)
    args = ap.parse_args(argv)
    if getattr(args, "jobs", 0) < 0:
        ap.error("-j: must be at least 1")
    if getattr(args, "max_runs", 1) < 1:
        ap.error("--max-runs: must be at least 1")
    if getattr(args, "poll", 1.0) <= 0:
        ap.error("--poll: must be a positive number of seconds")
    try:
        check_stdout(args)
        return {"run": cmd_run, "list": cmd_list, "slurm": cmd_slurm, "status": cmd_status,
                "merge": cmd_merge, "task": cmd_task}[args.cmd](args)
    except (RuntimeError, OSError) as e:
        say(PROG, str(e))
        return 1


def main(argv=None):
    return main_wrapper(PROG, run, sys.argv[1:] if argv is None else argv)


if __name__ == "__main__":
    sys.exit(main())
