#!/usr/bin/env python3
"""Make the certificates of a Dask cluster that lets in only its own machines.

    python scripts/cluster_certs.py DIR [--host ADDRESS_OR_NAME ...] [--days 365]

Writes into DIR a certificate authority (ca.pem; its key ca-key.pem, which signs and stays
here) and, signed by it, a key and certificate each for the scheduler, the workers and the
client (scheduler.pem and scheduler-key.pem, worker..., client...), naming the --host
machines (default 127.0.0.1 and localhost). Keys are readable by their owner alone. Copy
ca.pem with the scheduler's pair to the scheduler's machine, with the worker's pair to each
worker's, and keep the client's where campaigns start; then (docs/performance.md):

    dask scheduler --protocol tls --host HOST --tls-ca-file DIR/ca.pem \\
        --tls-cert DIR/scheduler.pem --tls-key DIR/scheduler-key.pem
    dask worker tls://HOST:8786 --tls-ca-file DIR/ca.pem --tls-cert DIR/worker.pem \\
        --tls-key DIR/worker-key.pem
    python -m studies.detectability --cluster tls://HOST:8786 --tls-certs DIR

A folder that holds a CA already is left as it is (exit status 1).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from uav_fault_estimator.campaigns.cluster_security import VALID_DAYS, make_certificates


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, metavar="DIR")
    parser.add_argument("--host", action="append", dest="hosts", metavar="ADDRESS_OR_NAME",
                        help="a machine of the cluster (repeat; default 127.0.0.1, localhost)")
    parser.add_argument("--days", type=int, default=VALID_DAYS,
                        help="how long the certificates hold (default %(default)s)")
    arguments = parser.parse_args()
    try:
        written = make_certificates(arguments.folder,
                                    arguments.hosts or ("127.0.0.1", "localhost"),
                                    arguments.days)
    except (FileExistsError, ValueError) as error:
        print(f"cluster_certs.py: {error}", file=sys.stderr)
        return 1
    print("\n".join(str(path) for path in written))
    return 0


if __name__ == "__main__":
    sys.exit(main())
