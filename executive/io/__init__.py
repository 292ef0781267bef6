"""Input/output: the only code that touches sockets, serial ports and buses.

Readers drain links and write the blackboard; writers (the commander) send what the tree asked.
"""
