"""Which cluster addresses a campaign takes, decided before anything connects (every socket
call that could send or resolve is made to fail here), and the certificates cluster_certs.py
makes."""

from __future__ import annotations

import argparse
import logging
import socket
import stat

import pytest
from cryptography import x509
from uav_fault_estimator.campaigns import campaign as campaigns
from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    CampaignOptions,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.campaigns.cluster_security import (
    CA_CERTIFICATE,
    CA_KEY,
    ROLES,
    ClusterAddressError,
    certificate_path,
    cluster_access,
    key_path,
    make_certificates,
)


@pytest.fixture
def no_network(monkeypatch):
    """Any attempt to connect, send or resolve a name fails the test."""
    def refuse(*_args, **_kwargs):
        raise AssertionError("network used")
    for name in ("connect", "connect_ex", "sendto", "send"):
        monkeypatch.setattr(socket.socket, name, refuse)
    for name in ("getaddrinfo", "gethostbyname", "create_connection"):
        monkeypatch.setattr(socket, name, refuse)


def options(*argv: str) -> CampaignOptions:
    parser = argparse.ArgumentParser()
    add_campaign_arguments(parser)
    return campaign_options(parser.parse_args(list(argv)))


@pytest.mark.timeout(30)
@pytest.mark.parametrize("address", ["tcp://10.0.0.1:8786", "10.0.0.1:8786",
                                     "tcp://scheduler.example.org:8786",
                                     "tcp://[2001:db8::1]:8786", "tcp://0.0.0.0:8786"])
def test_plain_tcp_off_this_machine_is_refused_in_one_line_before_connecting(no_network,
                                                                             address):
    with pytest.raises(ClusterAddressError, match=r"plain TCP to another machine") as refused:
        options("--cluster", address)
    assert "\n" not in str(refused.value)
    with pytest.raises(ClusterAddressError):  # nor does a Campaign built by hand connect
        Campaign(CampaignOptions(cluster=address)).client()
    allowed = options("--cluster", address, "--insecure-cluster")
    assert cluster_access(allowed.cluster, None, allowed.insecure_cluster).insecure


@pytest.mark.timeout(30)
@pytest.mark.parametrize("address", ["tcp://127.0.0.1:8786", "127.0.0.2:8786",
                                     "tcp://localhost:8786", "tcp://[::1]:8786"])
def test_plain_tcp_on_this_machine_is_taken(no_network, address):
    access = cluster_access(options("--cluster", address).cluster)
    assert (access.address, access.security, access.insecure) == (address, None, False)


@pytest.mark.timeout(30)
def test_tls_needs_the_certificates_and_other_schemes_are_refused(no_network, tmp_path):
    with pytest.raises(ClusterAddressError, match="needs --tls-certs"):
        options("--cluster", "tls://10.0.0.1:8786")
    with pytest.raises(ClusterAddressError, match=r"client\.pem"):
        options("--cluster", "tls://10.0.0.1:8786", "--tls-certs", str(tmp_path))
    with pytest.raises(ClusterAddressError, match="tls:// or, on this machine, tcp://"):
        options("--cluster", "ws://127.0.0.1:8786")
    with pytest.raises(ClusterAddressError, match="needs a tls:// address"):
        options("--cluster", "tcp://127.0.0.1:8786", "--tls-certs", str(tmp_path))
    with pytest.raises(ClusterAddressError, match="go with --cluster"):
        options("--insecure-cluster")
    make_certificates(tmp_path)
    access = cluster_access(options("--cluster", "tls://10.0.0.1:8786", "--tls-certs",
                                    str(tmp_path)).cluster, tmp_path)
    assert access.security.require_encryption and not access.insecure
    assert access.security.tls_client_cert == str(certificate_path(tmp_path, "client"))


@pytest.mark.timeout(30)
def test_a_script_says_the_refusal_in_one_line_and_exits_1(no_network, capsys):
    @exit_on_failed_tasks
    def main() -> int:
        options("--cluster", "tcp://10.0.0.1:8786")
        return 0

    assert main() == 1
    [line] = capsys.readouterr().err.splitlines()
    assert "--cluster tcp://10.0.0.1:8786: plain TCP to another machine" in line


@pytest.mark.timeout(30)
def test_the_insecure_cluster_is_said_once_on_connecting(no_network, monkeypatch, caplog):
    connected = []

    class Recorded:  # stands in for Dask's Client: nothing is connected
        def __init__(self, address, security, timeout):
            connected.append((address, security))

        def __enter__(self):
            return self

        def __exit__(self, *_exception):
            pass

    monkeypatch.setattr(campaigns, "Client", Recorded)
    with caplog.at_level(logging.WARNING), Campaign(CampaignOptions(
            cluster="tcp://10.0.0.1:8786", insecure_cluster=True)) as campaign:
        campaign.client()
        campaign.client()
    assert connected == [("tcp://10.0.0.1:8786", None)]
    [record] = caplog.records
    assert "anyone who can reach it can run code on its workers" in record.getMessage()


@pytest.mark.timeout(30)
def test_the_certificates_are_signed_by_their_ca_and_the_keys_private(tmp_path):
    written = make_certificates(tmp_path, ("10.0.0.1", "node2"), days=30)
    assert len(written) == 2 + 2 * len(ROLES)
    ca = x509.load_pem_x509_certificate((tmp_path / CA_CERTIFICATE).read_bytes())
    for role in ROLES:
        certificate = x509.load_pem_x509_certificate(certificate_path(tmp_path, role)
                                                     .read_bytes())
        certificate.verify_directly_issued_by(ca)
        names = certificate.extensions.get_extension_for_class(x509.SubjectAlternativeName)
        assert [str(n.value) for n in names.value] == ["10.0.0.1", "node2"]
        assert stat.S_IMODE(key_path(tmp_path, role).stat().st_mode) == 0o600
    assert stat.S_IMODE((tmp_path / CA_KEY).stat().st_mode) == 0o600
    with pytest.raises(FileExistsError, match="made once per cluster"):
        make_certificates(tmp_path)
