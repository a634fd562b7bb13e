"""Who a request comes from: the peer, or a trusted proxy's forwarded address, read as an IP address."""

from __future__ import annotations

from starlette.requests import Request

from causalplan.service.deps import client_address
from causalplan.service.owners import address_owner, key_owner, stored_owner
from causalplan.service.storage.records import MAX_OWNER_LENGTH
from causalplan.settings import Settings

BEHIND_PROXY = Settings(database_url="sqlite://", trusted_proxies=["192.0.2.10"])


def _request(forwarded: str | None, peer: str = "192.0.2.10") -> Request:
    headers = [(b"x-forwarded-for", forwarded.encode())] if forwarded is not None else []
    return Request({"type": "http", "headers": headers, "client": (peer, 4000), "path": "/", "method": "GET"})


def test_forwarded_hops_are_read_as_ip_addresses_and_others_ignored() -> None:
    assert client_address(_request("198.51.100.7"), BEHIND_PROXY) == "198.51.100.7"
    assert client_address(_request(" 2001:DB8::0001 "), BEHIND_PROXY) == "2001:db8::1"  # canonical form
    assert client_address(_request("198.51.100.7, not-an-address"), BEHIND_PROXY) == "198.51.100.7"
    assert client_address(_request("198.51.100.7, 10.0.0.1:443, x" * 3), BEHIND_PROXY) == "198.51.100.7"
    assert client_address(_request("a" * 500), BEHIND_PROXY) == "192.0.2.10"  # nothing valid: the proxy itself
    assert client_address(_request("198.51.100.7", peer="203.0.113.1"), BEHIND_PROXY) == "203.0.113.1"  # untrusted


def test_owners_are_never_cut_so_long_values_never_share_jobs() -> None:
    common = "participant:" + "p" * 200
    first, second = stored_owner(common + "1"), stored_owner(common + "2")
    assert first != second and max(len(first), len(second)) <= MAX_OWNER_LENGTH
    assert first.startswith("participant:sha256:")
    assert stored_owner("address:198.51.100.7") == address_owner("198.51.100.7").id == "address:198.51.100.7"
    assert len(key_owner("an-api-key-0123456789")) == len("key:") + 64  # the key's full SHA-256
