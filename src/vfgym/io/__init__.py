"""Files in and out: run folders (``runs``), per-tick trace CSV (``trace_csv``) and Value
Change Dumps of the pulse and encoder signals (``vcd``)."""
