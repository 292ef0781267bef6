"""Groot2 watches the executive: BehaviorTree.CPP's ``Groot2Publisher`` protocol over ZeroMQ, for a live run and a recorded one.

``executive run --groot2 [HOST:]PORT`` and ``executive replay FILE --groot2 [HOST:]PORT`` serve the
tree, its statuses, the blackboard and the transitions to any Groot2-protocol client (Groot2 itself,
``btview``). The tick thread only hands values over (:mod:`executive.observers.groot2.view`); the sockets live
on a thread of their own (:mod:`executive.observers.groot2.server`).
"""
