"""Readers and writers: canonical trace CSV, UR RTDE logs, Instron exports, campaign manifests.

Import the submodules directly, e.g. ``from palpbayes.io.trace_csv import read_trace``.
"""
