"""Readers of the experiment scripts' result files (edge.txt, eval.txt, experiment.txt: KEY: value)."""
import os


def keys(path):
    """KEY: value lines of a file as a dict (empty when the file is missing)."""
    kv = {}
    if os.path.isfile(path):
        for line in open(path):
            if ": " in line:
                k, v = line.split(": ", 1)
                kv[k.strip()] = v.strip()
    return kv
