"""Many flights or logs at once: on local worker processes or a Dask cluster (TLS)."""
