"""Readers and writers: trace CSV, UR RTDE logs, joint-angle traces, Instron exports, manifests.

Import the submodules directly, e.g. ``from palpbayes.io.trace_csv import read_trace``.
"""
