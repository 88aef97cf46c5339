"""Scale-out over Dask: many files as one batch (batch.py). Needs clpde[batch]; Dask is
imported only when a batch runs."""
