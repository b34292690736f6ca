#!/usr/bin/env python3
"""Rank correlation (Spearman) of per-tile disorder signals with the per-tile error.

Usage: scripts/signal-correlation.py OUT_DIR [OUT_DIR ...]
Each OUT_DIR is a `neo frames ... --tile-stats` output (tiles.jsonl). Frames that start a
shot (every tile from scratch) are skipped. `same`: the signal of the frame itself; `next`:
the signal of frame f-1 (what the frame controller has before sorting frame f).
"""
import json
import sys


def ranks(v):
    order = sorted(range(len(v)), key=lambda i: v[i])
    r = [0.0] * len(v)
    i = 0
    while i < len(v):
        j = i
        while j + 1 < len(v) and v[order[j + 1]] == v[order[i]]:
            j += 1
        for k in range(i, j + 1):
            r[order[k]] = (i + j) / 2.0
        i = j + 1
    return r


def spearman(x, y):
    if len(x) < 3:
        return float("nan")
    rx, ry = ranks(x), ranks(y)
    mx, my = sum(rx) / len(rx), sum(ry) / len(ry)
    sxy = sum((a - mx) * (b - my) for a, b in zip(rx, ry))
    sxx = sum((a - mx) ** 2 for a in rx)
    syy = sum((b - my) ** 2 for b in ry)
    return sxy / (sxx * syy) ** 0.5 if sxx > 0 and syy > 0 else float("nan")


SIGNALS = ["wb_descents", "wb_behind", "wb_reach", "merge_inversions", "incoming_share", "outgoing_share"]


def main():
    print("| run | pairs | target | " + " | ".join(SIGNALS) + " |")
    print("|---|---|---|" + "---|" * len(SIGNALS))
    for d in sys.argv[1:]:
        frames = [json.loads(l) for l in open(f"{d}/tiles.jsonl")]
        for f in frames:
            n = len(f["current"])
            f["incoming_share"] = [f["incoming"][i] / max(1, f["current"][i]) for i in range(n)]
            f["outgoing_share"] = [f["outgoing"][i] / max(1, f["current"][i]) for i in range(n)]
        for mode in ["same", "next"]:
            for target in ["abs_error", "inversions"]:
                xs = {s: [] for s in SIGNALS}
                ys = []
                for k, f in enumerate(frames):
                    if all(f["from_scratch"]) or (mode == "next" and k == 0):
                        continue
                    src = f if mode == "same" else frames[k - 1]
                    for i in range(len(f["current"])):
                        if f["current"][i] == 0 or f["from_scratch"][i]:
                            continue
                        ys.append(f[target][i])
                        for s in SIGNALS:
                            # merge inversions and shares always of the frame itself
                            srcs = f if s in ("merge_inversions", "incoming_share", "outgoing_share") else src
                            xs[s].append(srcs[s][i])
                cells = " | ".join(f"{spearman(xs[s], ys):.2f}" for s in SIGNALS)
                print(f"| {d.rstrip('/').split('/')[-1]} ({mode}) | {len(ys)} | {target} | {cells} |")


main()
