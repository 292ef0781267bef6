"""Benchmarks of the executive: tick cost, MAVLink ingest, CAN decode, reaction latency, simulator speed, start-up and memory.

Run them all with ``python -m benchmarks`` (see the manual's Benchmarks page, docs/benchmarks.md); each module's ``run`` returns its rows.
"""
