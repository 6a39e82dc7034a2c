"""Sub-commands of the ``vfgym`` command line, one module each (see :mod:`vfgym.cli`)."""
