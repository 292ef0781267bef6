"""Sample-taking instruments: the sampler interface and the simulated one (:mod:`.sampler`), and which back end a mission uses (:mod:`.backends`).

A back end touching a device lives with the I/O (``serial``: :mod:`executive.instruments.serial`);
every back end, built in or a plugin's, is found through :mod:`executive.registry`.
"""
