#!/usr/bin/env python3
"""Volux against the reference libraries on their own test data (issue 40).

For every file of the corpus (corpus.py) the reference library decodes it (reference.py),
Volux converts it (`volux convert FILE OUT.nrrd [OPTIONS]`), and the two are compared:
values (exact for lossless data, within the codec's tolerance against the reference decoder
for lossy data) and geometry (the index-to-LPS affine; a Volux grid whose axes are a
permutation or reversal of the reference's describes the same volume and is compared as such).
Each file is classified:

- exact: the same values at the same places;
- differs: Volux read something else without a word (a silent misread: CI fails);
- noted: Volux read something else and said so in a note (a conversion that loses precision);
- refused: Volux exited non-zero with one line naming why;
- unclear: refused with more than one line, or with nothing;
- crash: a panic, a signal, or more than the time limit (CI fails).

Files the reference library cannot decode and files that hold no image are run too (no crash,
one line), and listed apart. The table goes to docs/conformance.md; `--check` makes the exit
status non-zero on any silent difference or crash, or an exact share below `--min-exact`.
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import corpus as corpus_mod  # noqa: E402
import reference  # noqa: E402

TIME_LIMIT = 60.0


GNU_TIME = "/usr/bin/time"


def run_measured(volux: str, path: str, out: Path, args: tuple):
    """Runs `volux convert`; returns (exit code or None on timeout, stderr, seconds, the
    peak memory of volux in MiB).

    The memory is what GNU time reports for the volux process it starts: a child forked by
    this (large) Python process would report Python's own resident size as its peak, since
    ru_maxrss survives exec. Without GNU time, the figure is os.wait4's, an upper bound."""
    t0 = time.monotonic()
    with tempfile.TemporaryFile(mode="w+", errors="replace") as err_f, tempfile.NamedTemporaryFile(mode="r") as rss_f:
        cmd = [volux, "convert", path, str(out), *args]
        timed = os.path.exists(GNU_TIME)
        if timed:
            cmd = [GNU_TIME, "-f", "%M", "-o", rss_f.name, *cmd]
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err_f, start_new_session=True)
        deadline = t0 + TIME_LIMIT
        while True:
            pid, status, ru = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() > deadline:
                os.killpg(proc.pid, 9)
                os.wait4(proc.pid, 0)
                err_f.seek(0)
                return None, err_f.read(), TIME_LIMIT, 0.0
            time.sleep(0.005)
        code = os.waitstatus_to_exitcode(status)
        secs = time.monotonic() - t0
        err_f.seek(0)
        err = err_f.read()
        rss = ru.ru_maxrss / 1024.0
        if timed:
            # GNU time appends "Command exited with non-zero status N" / "Command terminated
            # by signal N" to its output file, and the figure last.
            text = rss_f.read()
            figures = [w for w in text.split() if w.isdigit()]
            if figures:
                rss = int(figures[-1]) / 1024.0
            if "terminated by signal" in text:
                code = -1
        return code, err, secs, rss


def read_volux_nrrd(path: Path):
    import nrrd

    data, hdr = nrrd.read(str(path))
    data = np.asarray(data).astype(np.float64)
    kinds = [k.lower() for k in hdr.get("kinds", ["domain"] * data.ndim)]
    dirs = hdr["space directions"]
    spatial = [i for i in range(data.ndim) if dirs[i] is not None and not np.any(np.isnan(np.asarray(dirs[i], float)))]
    others = [i for i in range(data.ndim) if i not in spatial]
    d = data.transpose(spatial + others)
    assert str(hdr.get("space", "")).lower() in ("left-posterior-superior", "lps"), hdr.get("space")
    affine = reference.affine_from(hdr.get("space origin", np.zeros(3)), [np.asarray(dirs[i], float) for i in spatial])
    return d, affine, kinds


def _complete(affine: np.ndarray, dims) -> np.ndarray:
    """Replaces the columns of singleton axes by unit normals, so that an axis along which
    there is one sample (a single slice) does not decide the comparison."""
    a = affine.copy()
    single = [i for i in range(3) if dims[i] == 1]
    if len(single) == 1:
        k = single[0]
        i, j = [x for x in range(3) if x != k]
        n = np.cross(a[:3, i], a[:3, j])
        norm = np.linalg.norm(n)
        if norm > 0:
            a[:3, k] = n / norm * (1 if (k - i) % 3 == 1 or k == 2 else 1)
    elif len(single) >= 2:
        for k in single:
            a[:3, k] = np.eye(3)[:, k]
    return a


def compare(ref: reference.Reference, vol: np.ndarray, vol_aff: np.ndarray):
    """(ok, message): whether Volux's volume is the reference's, and what differs."""
    ref_color = ref.values.ndim == 4
    vol_color = vol.ndim == 4
    if ref_color != vol_color:
        if ref_color:
            return False, f"colour ({ref.values.shape[3]} samples) read as one scalar"
        return False, f"one scalar read as {vol.shape[3]} components"
    dims_ref = ref.values.shape[:3]
    mapped = vol
    if ref.affine is not None:
        a_ref = _complete(ref.affine, dims_ref)
        a_vol = _complete(vol_aff, vol.shape[:3])
        if np.linalg.matrix_rank(a_vol[:3, :3]) < 3 or np.linalg.matrix_rank(a_ref[:3, :3]) < 3:
            return False, "degenerate geometry"
        m = np.linalg.inv(a_vol) @ a_ref
        rot = m[:3, :3]
        perm = np.rint(rot)
        ok_perm = np.all(np.abs(rot - perm) < 1e-3) and all(np.sum(np.abs(perm), axis=0) == 1) and all(np.sum(np.abs(perm), axis=1) == 1)
        if not ok_perm:
            return False, "geometry differs: " + describe(ref.affine, vol_aff)
        axes = [int(np.argmax(np.abs(perm[:, a]))) for a in range(3)]
        mapped = vol.transpose(axes + ([3] if vol_color else []))
        for a in range(3):
            b = axes[a]
            sign = perm[b, a]
            t = m[b, 3]
            want = 0.0 if sign > 0 else vol.shape[b] - 1
            if dims_ref[a] > 1 and abs(t - want) > 1e-3:
                return False, "geometry differs (origin): " + describe(ref.affine, vol_aff)
            if sign < 0:
                mapped = np.flip(mapped, axis=a)
    if mapped.shape != ref.values.shape:
        return False, f"dims {list(mapped.shape)} instead of {list(ref.values.shape)}"
    want = ref.values
    finite = np.isfinite(want)
    if not finite.all():
        # Volux replaces NaN and infinities by the data's extremes, with a note.
        if not np.array_equal(mapped[finite], want[finite].astype(np.float32).astype(np.float64)):
            return False, "values differ where the reference is finite"
        return False, f"{int((~finite).sum())} non-finite values replaced (Volux's policy)"
    if ref.tol == 0:
        same = np.array_equal(mapped, want.astype(np.float32).astype(np.float64)) or np.array_equal(mapped, want)
        if not same:
            diff = np.abs(mapped - want)
            worst = np.unravel_index(np.argmax(diff), diff.shape)
            rel = float(np.max(diff / np.maximum(np.abs(want), 1e-30)))
            return False, (
                f"values differ at {int(np.sum(diff.ravel() > 0))} of {diff.size} samples "
                f"(worst at {list(map(int, worst))}: {mapped[worst]:.9g} instead of {want[worst]:.9g}; "
                f"largest relative difference {rel:.3g})"
            )
    else:
        err = np.abs(mapped - want).max()
        if err > ref.tol:
            return False, f"values differ by up to {err:.3g} (lossy tolerance {ref.tol:g})"
    return True, ""


def explained(msg: str, notes: str) -> bool:
    """Whether a note of Volux's says what differs: values rounded to float32 (a conversion
    it names), or non-finite values replaced. Any other difference is silent, whatever
    else the notes say."""
    n = notes.lower()
    if "non-finite values replaced" in msg:
        return "non-finite" in n
    if msg.startswith("values differ at") and "converted" in n and ("precision" in n or "float32" in n):
        rel = float(msg.rsplit("largest relative difference ", 1)[1].rstrip(")"))
        return rel <= 2.0**-23
    return False


def describe(a_ref, a_vol) -> str:
    def fmt(a):
        sp = np.linalg.norm(a[:3, :3], axis=0)
        return f"origin {np.round(a[:3, 3], 3).tolist()} spacing {np.round(sp, 4).tolist()}"

    return f"Volux {fmt(a_vol)}, reference {fmt(a_ref)}"


def one_line(err: str) -> list[str]:
    return [l for l in err.splitlines() if l.strip() and not l.startswith("wrote ")]


def notes_of(err: str) -> str:
    return " ".join(l for l in err.splitlines() if l.startswith("note:"))


def classify(volux, entry, ref, tmp: Path, idx: int):
    path, kind, source, scope = entry
    args = ref.args if ref is not None else ()
    out = tmp / f"out{idx}.nrrd"
    rc, err, secs, rss = run_measured(volux, path, out, args)
    row = {"file": path, "kind": kind, "source": source, "scope": scope, "args": list(args), "secs": round(secs, 3), "rss_mib": round(rss, 1), "size": reference.file_size(path)}
    lines = one_line(err)
    errors = [l for l in lines if not l.startswith("note:")]
    if rc is None:
        row.update(status="crash", detail=f"no answer in {TIME_LIMIT:.0f} s")
    elif rc != 0:
        if rc == 101 or rc < 0 or "panicked" in err:
            row.update(status="crash", detail=(errors or ["(no message)"])[-1][:300])
        elif len(errors) == 1:
            row.update(status="refused", detail=errors[0][:300])
        else:
            row.update(status="unclear", detail=" | ".join(errors)[:300] or "(no message)")
        if out.exists():
            row["detail"] += " [an output file was left behind]"
            row["status"] = "crash"
    elif ref is None:
        row.update(status="read", detail="")
    else:
        notes = notes_of(err)
        try:
            vol, aff, _ = read_volux_nrrd(out)
            ok, msg = compare(ref, vol, aff)
        except Exception as e:  # noqa: BLE001
            ok, msg = False, f"output unreadable: {e}"
        if ok and ref.expect_note and ref.expect_note.lower() not in notes.lower():
            ok, msg = False, f"no note says that {ref.expect_note} was applied"
        if ok:
            row.update(status="exact", detail="")
        else:
            row.update(status="noted" if explained(msg, notes) else "differs", detail=msg[:300], notes=notes[:300])
        if not ok and ref.why_no_geometry:
            row["detail"] += f" (geometry not compared: {ref.why_no_geometry})"
    if out.exists():
        out.unlink()
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--volux", required=True)
    ap.add_argument("--work", default=None)
    ap.add_argument("--markdown", default=None, help="write the table here (docs/conformance.md)")
    ap.add_argument("--json", default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--min-exact", type=float, default=0.0, help="least share of exact reads (0..1)")
    ap.add_argument("--only", default=None, help="substring of the paths to run")
    a = ap.parse_args()
    work = Path(a.work or tempfile.mkdtemp(prefix="volux-conformance-"))
    entries = corpus_mod.corpus(work / "corpus")
    if a.only:
        entries = [e for e in entries if a.only in e[0]]
    tmp = work / "out"
    tmp.mkdir(parents=True, exist_ok=True)
    jobs = []
    for e in entries:
        try:
            refs = reference.for_file(e[0], e[1])
            why = ""
        except reference.NoReference as x:
            refs, why = [None], f"reference: {x}"
        except reference.NotImage as x:
            refs, why = [None], f"not an image: {x}"
        for r in refs:
            jobs.append((e, r, why))
    rows = []
    with cf.ThreadPoolExecutor(a.jobs) as pool:
        futs = [pool.submit(classify, a.volux, e, r, tmp, i) for i, (e, r, _) in enumerate(jobs)]
        for (e, r, why), f in zip(jobs, futs):
            row = f.result()
            if r is None:
                row["reference"] = why
            rows.append(row)
    report(rows, a)
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1))
    s = summary(rows)
    print(json.dumps(s["counts"]), f"exact share {s['share']:.3f}")
    if a.check:
        bad = [r for r in rows if r["status"] in ("differs", "crash", "unclear")]
        slow = [r for r in rows if r["status"] in ("refused",) and r["size"] < 1 << 20 and (r["secs"] > 1.0 or r["rss_mib"] > 256)]
        for r in bad + slow:
            print(f"FAIL {r['status']}: {r['file']} {' '.join(r['args'])}: {r['detail']}", file=sys.stderr)
        if s["share"] < a.min_exact:
            print(f"FAIL exact share {s['share']:.3f} below {a.min_exact}", file=sys.stderr)
            sys.exit(1)
        if bad or slow:
            sys.exit(1)


def summary(rows):
    counted = [r for r in rows if r["scope"] == "in" and "reference" not in r]
    counts = {}
    for r in counted:
        counts[r["status"]] = counts.get(r["status"], 0) + 1
    share = counts.get("exact", 0) / max(1, len(counted))
    return {"counts": counts, "share": share, "counted": counted}


def report(rows, a):
    if not a.markdown:
        return
    s = summary(rows)
    lines = [
        "# Conformance: Volux against the reference libraries",
        "",
        "Written by `.ci/conformance/run.py` (run by `cargo test -p volux-cli --test conformance`,",
        "which CI runs with the reference libraries installed by `.ci/conformance/setup`). Each",
        "file the reference library decodes is converted by `volux convert FILE OUT.nrrd` and",
        "compared with it: values exact (lossy codecs: within the codec's tolerance against the",
        "reference decoder) and geometry (index to LPS). See the script's docstring for the classes.",
        "",
        "## Summary",
        "",
        "| class | files |",
        "|---|---|",
    ]
    for k in ("exact", "noted", "refused", "differs", "unclear", "crash"):
        lines.append(f"| {k} | {s['counts'].get(k, 0)} |")
    lines += [
        f"| **counted** | **{len(s['counted'])}** (exact: **{100 * s['share']:.1f} %**) |",
        "",
        "By source (counted files):",
        "",
        "| source | exact | noted | refused | differs | unclear | crash |",
        "|---|---|---|---|---|---|---|",
    ]
    by_src = {}
    for r in s["counted"]:
        by_src.setdefault(r["source"], {}).setdefault(r["status"], 0)
        by_src[r["source"]][r["status"]] += 1
    for src, c in sorted(by_src.items()):
        lines.append("| " + " | ".join([src] + [str(c.get(k, 0)) for k in ("exact", "noted", "refused", "differs", "unclear", "crash")]) + " |")
    lines += ["", "## Files not read exactly", "", "| file | options | class | what |", "|---|---|---|---|"]
    for r in s["counted"]:
        if r["status"] != "exact":
            lines.append(f"| `{short(r['file'])}` | {' '.join(r['args'])} | {r['status']} | {esc(r['detail'])} |")
    others = [r for r in rows if r not in s["counted"]]
    lines += [
        "",
        "## Not counted",
        "",
        "Files the reference library does not decode, files without an image, and formats outside",
        "Volux's list; Volux must still answer them in one line, without a crash.",
        "",
        "| file | scope | reference | Volux |",
        "|---|---|---|---|",
    ]
    for r in others:
        ref = r.get("reference", "decoded")
        lines.append(f"| `{short(r['file'])}` | {r['scope']} | {esc(ref)} | {r['status']}: {esc(r['detail'])} |")
    lines += ["", "## Exactly read", "", ", ".join(f"`{short(r['file'])}`{' ' + ' '.join(r['args']) if r['args'] else ''}" for r in s["counted"] if r["status"] == "exact"), ""]
    Path(a.markdown).write_text("\n".join(lines))


def short(p: str) -> str:
    for marker in ("site-packages/", "corpus/"):
        if marker in p:
            return p.split(marker, 1)[1]
    return p


def esc(s: str) -> str:
    return s.replace("|", "\\|").replace("\n", " ")


if __name__ == "__main__":
    main()
