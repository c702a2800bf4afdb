"""What the package raises. Every exception derives from omega.Error; `code` is the daemon's
error code (docs/protocol.md, "Error codes") where the daemon sent one."""
from __future__ import annotations


class Error(Exception):
    """Base of every error this package raises (besides ValueError/TypeError for bad arguments)."""

    code: str | None = None

    def __init__(self, message: str, code: str | None = None):
        super().__init__(message)
        self.message = message
        if code is not None:
            self.code = code


class DaemonError(Error):
    """omegad answered with an `error` frame: `code` (e.g. scene_invalid, unknown_job,
    invalid_state, auth_failed) and its `message` as sent. Codes unknown to this package are
    passed through unchanged (new ones may be added without a protocol version change)."""

    def __init__(self, code: str, message: str, address: str = ""):
        text = f"{message} ({code})" if message else code
        super().__init__(f"{address}: {text}" if address else text, code)
        self.message = message
        self.address = address


class ConnectionFailed(Error, ConnectionError):
    """The daemon could not be reached, TLS failed, or the connection closed or broke."""


class Timeout(Error, TimeoutError):
    """No reply in time. The connection itself stays usable."""


class ProtocolError(Error):
    """The daemon sent something this client cannot read. `code` is the name docs/protocol.md
    gives the failure (bad_magic, truncated, missing_field, wrong_type, ...)."""
