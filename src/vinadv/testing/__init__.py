"""Support code for the tests and benchmarks: synthetic inputs made without trained weights or a real run.

`planners`: hand-set VIN weights that plan (`planning_vin`, `exact_vin`) or do not (`random_vin`); `store`: random
well-formed `PairRecords` (`random_records`); `classify`: path pairs from expert paths (`synthetic_pairs`).
No production module imports this package (tests/test_layers.py checks it).
"""
