"""Tasks: what one block of a study runs over its trials (the GA's ``evolve``, ``categorise``).

A study is a sequence of blocks; a block runs one task over its trials. Each task is one module
here (its block config, its trials, what it shows and accepts, its simulated participant);
:mod:`emogen.tasks.protocol` is the protocol they share and the registry the study layer drives
them through.
"""
