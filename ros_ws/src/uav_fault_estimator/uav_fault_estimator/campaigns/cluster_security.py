"""Who may join a campaign's Dask cluster: mutual TLS with certificates of the user's own
certificate authority, and a refusal, before any connection, of a plain-TCP address off
this machine. No ROS here.

A Dask scheduler runs whatever a client submits, and its workers run it: on plain TCP,
anyone who can reach the scheduler's port can. With TLS (Dask's `tls://` addresses and
`distributed.security.Security`) the scheduler, each worker and each client prove
themselves with a certificate signed by one CA, and take only peers who do the same; a
CA made for one cluster lets in its own machines and no one else. make_certificates is
that CA and its certificates, written by hand on the `cryptography` package because Dask
makes only throw-away ones (`Security.temporary()`, for one process).
"""

from __future__ import annotations

import datetime
import ipaddress
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID
from distributed.comm.addressing import parse_address, parse_host_port
from distributed.security import Security
from uav_common.loopback import is_loopback

ROLES = ("scheduler", "worker", "client")
CA_CERTIFICATE = "ca.pem"
CA_KEY = "ca-key.pem"  # signs new certificates; need not leave the machine that made it
VALID_DAYS = 365
INSECURE_WARNING = ("the Dask cluster at {address} is plain TCP off this machine: anyone "
                    "who can reach it can run code on its workers (use tls:// and "
                    "--tls-certs; docs/security.md)")


class ClusterAddressError(ValueError):
    """A cluster address refused before connecting: the message says why, in one line."""


def certificate_path(folder: Path, role: str) -> Path:
    """The certificate of a role (ROLES) in a certificates folder."""
    return Path(folder) / f"{role}.pem"


def key_path(folder: Path, role: str) -> Path:
    """The private key of a role (ROLES) in a certificates folder."""
    return Path(folder) / f"{role}-key.pem"


def make_certificates(folder: Path, hosts: Sequence[str] = ("127.0.0.1", "localhost"),
                      days: int = VALID_DAYS) -> list[Path]:
    """A CA and, for each of ROLES, a key and a certificate it signs, valid for days and
    naming hosts (addresses or names of the cluster's machines); written into folder
    (created), keys readable by their owner alone (0600). FileExistsError when folder
    holds a CA already: a new CA would lock out every machine given the old one's
    certificates. Returns the files written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if (folder / CA_CERTIFICATE).exists():
        raise FileExistsError(f"{folder / CA_CERTIFICATE} exists: certificates are made once "
                              "per cluster (remove the folder to start over)")
    now = datetime.datetime.now(datetime.UTC)
    ca_key = ec.generate_private_key(ec.SECP256R1())
    ca_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "uav fault diagnostics CA")])
    ca = (_builder(ca_name, ca_name, ca_key.public_key(), now, days)
          .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
          .add_extension(x509.KeyUsage(**_usage(key_cert_sign=True, crl_sign=True)),
                         critical=True)
          .sign(ca_key, hashes.SHA256()))
    written = [_write_key(folder / CA_KEY, ca_key), _write_certificate(folder / CA_CERTIFICATE,
                                                                       ca)]
    names = x509.SubjectAlternativeName([_general_name(host) for host in hosts])
    for role in ROLES:
        key = ec.generate_private_key(ec.SECP256R1())
        subject = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, f"dask {role}")])
        certificate = (_builder(subject, ca_name, key.public_key(), now, days)
                       .add_extension(x509.BasicConstraints(ca=False, path_length=None),
                                      critical=True)
                       .add_extension(x509.KeyUsage(**_usage(digital_signature=True,
                                                             key_agreement=True)),
                                      critical=True)
                       .add_extension(x509.ExtendedKeyUsage(
                           [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]),
                           critical=False)
                       .add_extension(names, critical=False)
                       .sign(ca_key, hashes.SHA256()))
        written += [_write_key(key_path(folder, role), key),
                    _write_certificate(certificate_path(folder, role), certificate)]
    return written


def security(folder: Path, roles: Sequence[str] = ("client",)) -> Security:
    """Dask's Security for some of ROLES (one process may be all three: a LocalCluster)
    from a certificates folder: TLS required, the folder's CA the only one trusted.
    ClusterAddressError naming the files that are missing."""
    folder = Path(folder)
    files = {"tls_ca_file": folder / CA_CERTIFICATE}
    for role in roles:
        files |= {f"tls_{role}_cert": certificate_path(folder, role),
                  f"tls_{role}_key": key_path(folder, role)}
    missing = [str(path) for path in files.values() if not path.is_file()]
    if missing:
        raise ClusterAddressError(f"--tls-certs {folder}: no {', '.join(missing)} "
                                  "(scripts/cluster_certs.py makes them)")
    return Security(require_encryption=True,
                    **{option: str(path) for option, path in files.items()})


@dataclass(frozen=True)
class ClusterAccess:
    """How a campaign reaches its scheduler: the address, the Security for TLS (None on
    loopback or refused-but-allowed TCP), and whether it is plain TCP off this machine
    (allowed by --insecure-cluster; said once on connecting)."""

    address: str
    security: Security | None
    insecure: bool


def cluster_access(address: str, tls_certs: Path | None = None,
                   insecure_cluster: bool = False) -> ClusterAccess:
    """Check a cluster address without connecting (no name is resolved: a name other than
    localhost counts as another machine): tls:// needs tls_certs; tcp:// (or no scheme) is
    taken on a loopback address, elsewhere only with insecure_cluster; any other scheme is
    refused. ClusterAddressError saying why."""
    try:
        scheme, location = parse_address(address)
        host, _ = parse_host_port(location)
    except ValueError as error:
        raise ClusterAddressError(f"--cluster {address}: not an address ({error})") from None
    if scheme == "tls":
        if tls_certs is None:
            raise ClusterAddressError(f"--cluster {address}: a tls:// address needs "
                                      "--tls-certs DIR (scripts/cluster_certs.py makes it)")
        return ClusterAccess(address, security(tls_certs), insecure=False)
    if scheme != "tcp":
        raise ClusterAddressError(f"--cluster {address}: tls:// or, on this machine, tcp://")
    if tls_certs is not None:
        raise ClusterAddressError(f"--cluster {address}: --tls-certs needs a tls:// address")
    off_machine = not is_loopback(host)
    if off_machine and not insecure_cluster:
        raise ClusterAddressError(
            f"--cluster {address}: plain TCP to another machine lets anyone who reaches it "
            "run code on the workers; use tls:// with --tls-certs (or --insecure-cluster)")
    return ClusterAccess(address, None, insecure=off_machine)


def _builder(subject: x509.Name, issuer: x509.Name, public_key: ec.EllipticCurvePublicKey,
             now: datetime.datetime, days: int) -> x509.CertificateBuilder:
    return (x509.CertificateBuilder().subject_name(subject).issuer_name(issuer)
            .public_key(public_key).serial_number(x509.random_serial_number())
            .not_valid_before(now - datetime.timedelta(minutes=5))  # clocks a little apart
            .not_valid_after(now + datetime.timedelta(days=days)))


def _usage(**allowed: bool) -> dict[str, bool]:
    """x509.KeyUsage's nine flags, the allowed ones True."""
    flags = ("digital_signature", "content_commitment", "key_encipherment",
             "data_encipherment", "key_agreement", "key_cert_sign", "crl_sign",
             "encipher_only", "decipher_only")
    return {flag: allowed.get(flag, False) for flag in flags}


def _general_name(host: str) -> x509.GeneralName:
    try:
        return x509.IPAddress(ipaddress.ip_address(host))
    except ValueError:
        return x509.DNSName(host)


def _write_key(path: Path, key: ec.EllipticCurvePrivateKey) -> Path:
    """The key as PEM, created 0600 (never readable by others, not even for a moment)."""
    data = key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                             serialization.NoEncryption())
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(descriptor, "wb") as file:
        file.write(data)
    return path


def _write_certificate(path: Path, certificate: x509.Certificate) -> Path:
    path.write_bytes(certificate.public_bytes(serialization.Encoding.PEM))
    return path
