"""Python client for omegad, the Omega render daemon (docs/python.md).

    import omega
    with omega.connect("unix:/run/omega/omegad.sock") as c:
        job = c.submit("scenes/cornell-box.yaml", spp=64)
        for ev in job.watch():
            print(ev.kind, ev)
        job.fetch().save("cornell.exr")

The protocol (docs/protocol.md) needs only the standard library; numpy, when installed, turns
tiles and images into float arrays (Tile.pixels, Image.pixels, .decode()).
"""
from .connection import Address, default_address, parse_address
from .errors import ConnectionFailed, DaemonError, Error, ProtocolError, Timeout
from .jobs import (FINAL_STATES, JOB_STATES, Client, Done, Image, Job, JobInfo, Progress, ProgressUpdate, Tile,
                   connect)

__version__ = "0.1.0"

__all__ = [
    "connect", "Client", "Job", "JobInfo", "Progress", "ProgressUpdate", "Tile", "Done", "Image",
    "Error", "DaemonError", "ConnectionFailed", "Timeout", "ProtocolError",
    "Address", "parse_address", "default_address", "JOB_STATES", "FINAL_STATES", "__version__",
]
