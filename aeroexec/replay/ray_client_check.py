"""Why `--executor ray://HOST:PORT` cannot connect, said before Ray Client says nothing.

Ray Client's own failures are slow and vague: a port nobody listens on, and a cluster
with token authentication reached without the token, both end after ~30 s of retries as
"ray client connection timeout" (the refusal is only logged on the head). So before
`ray.init("ray://...")` one PING goes to the head's Ray Client proxy, as Ray's client
sends it (with the token header when this process is in token mode), and its answer
names the cause at once: nothing answers at HOST:PORT, the cluster wants a token and
this process sends none, or it refused the token. After a failed `ray.init`, `hint`
turns the two messages of the head's proxy into their causes.

Ray is optional: only `ray_executor` imports this module. Ray's authentication helpers
are private; if they move, the check is skipped and Ray's own message stands.
"""

from __future__ import annotations

import os
from urllib.parse import urlsplit

import grpc
from ray.core.generated import ray_client_pb2, ray_client_pb2_grpc

#: How long (s) the PING may take: the proxy answers it itself, without starting anything.
PING_TIMEOUT_S = 10.0
AUTH_MODE = "RAY_AUTH_MODE"
#: Where Ray looks for the token of a client in token mode, for messages.
TOKEN_PLACES = "RAY_AUTH_TOKEN, RAY_AUTH_TOKEN_PATH or ~/.ray/auth_token"
SEE = "see docs/fleet.md#when-ray-client-cannot-connect"


def _token_metadata() -> tuple[tuple[str, str], ...]:
    try:
        from ray._private.authentication.grpc_authentication_client_interceptor import (
            _get_authentication_metadata_tuple,
        )
    except ImportError:  # Ray without token authentication (< 2.5x): nothing to send
        return ()
    return tuple(_get_authentication_metadata_tuple())


def _token_mode() -> bool:
    return os.environ.get(AUTH_MODE, "").strip().lower() == "token"


def problem(address: str) -> str | None:
    """What keeps this process from the Ray Client proxy at `address` (ray://HOST:PORT),
    or None when it answers a PING."""
    parts = urlsplit(address)
    host, port = parts.hostname or "", parts.port or 10001
    target = f"{host}:{port}" if ":" not in host else f"[{host}]:{port}"
    with grpc.insecure_channel(target) as channel:
        stub = ray_client_pb2_grpc.RayletDriverStub(channel)
        request = ray_client_pb2.ClusterInfoRequest(type=ray_client_pb2.ClusterInfoType.PING)
        try:
            stub.ClusterInfo(request, timeout=PING_TIMEOUT_S, metadata=_token_metadata())
        except grpc.RpcError as exc:
            return _refusal(exc.code(), target)  # type: ignore[attr-defined]
    return None


def _refusal(code: grpc.StatusCode, target: str) -> str:
    if code is grpc.StatusCode.UNAUTHENTICATED:
        if not _token_mode():
            return (
                f"the cluster at {target} uses Ray's token authentication and this process "
                f"does not: set {AUTH_MODE}=token and the cluster's token ({TOKEN_PLACES}) "
                f"where aeroexec runs, as on every node ({SEE})"
            )
        return (
            f"the cluster at {target} refused this process's token ({TOKEN_PLACES}): it is "
            f"not the one the head was started with ({SEE})"
        )
    if code is grpc.StatusCode.UNAVAILABLE:
        return (
            f"nothing answers at {target}: is the head running, with "
            "`--ray-client-server-port` this port (Ray's default 10001), and is the port "
            f"reachable from here? ({SEE})"
        )
    if code is grpc.StatusCode.DEADLINE_EXCEEDED:
        return (
            f"{target} did not answer within {PING_TIMEOUT_S:.0f} s (a firewall that drops "
            f"packets, or a head too busy to answer) ({SEE})"
        )
    return f"the Ray Client proxy at {target} answered {code.name} ({SEE})"


def hint(message: str) -> str:
    """The cause of a failed `ray.init("ray://...")`, from the head proxy's message."""
    if "Starting Ray client server failed" in message:
        return (
            "; the head started a Ray Client server for this client and it exited before "
            "serving: its log is ray_client_server_<port>.err in the head's session logs "
            f"(/tmp/ray/session_latest/logs by default) ({SEE})"
        )
    if "Proxy failed to Connect to backend" in message:
        return (
            "; the head's Ray Client server for this client did not answer within "
            "RAY_CLIENT_SERVER_CHECK_CHANNEL_TIMEOUT_S (30 s by default): on a busy head, "
            f"start the head with it set higher (180) ({SEE})"
        )
    if "ray client connection timeout" in message:
        return (
            "; the head's Ray Client proxy answered but did not let this client in within "
            f"Ray's retries (~30 s) ({SEE})"
        )
    return ""
