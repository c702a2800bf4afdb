"""TLS on TCP (tls_cert/tls_key): the HMAC handshake and a whole job over TLS, a plaintext client
on the TLS port is cut with a log line, and a bad key file is refused at start-up."""
import os
import ssl
import subprocess

import harness
from harness import OMEGAD, Daemon, Test, op, small_cornell, wait_state

TOKEN = "alice-token-0123456789"


def make_cert(tmp):
    cert, key = os.path.join(tmp, "cert.pem"), os.path.join(tmp, "key.pem")
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", key, "-out", cert,
                    "-days", "1", "-subj", "/CN=localhost", "-addext", "subjectAltName=DNS:localhost,IP:127.0.0.1"],
                   check=True, capture_output=True, timeout=60)
    return cert, key


def tls_client(d, cert):
    c = op.Client(d.tcp, client_name=None)
    ctx = ssl.create_default_context(cafile=cert)
    c.sock = ctx.wrap_socket(c.sock, server_hostname="127.0.0.1")
    c.send(op.hello(c.new_id(), "tls-test"))
    c.welcome = c.recv()
    return c


def test_tls_session(tmp, daemons):
    cert, key = make_cert(tmp)
    d = Daemon(tmp, config=f"tls_cert: {cert}\ntls_key: {key}\ntcp_users: {{alice: {TOKEN}}}\n").start()
    daemons.append(d)
    d.wait_log(r"\(TCP over TLS\)")
    c = tls_client(d, cert)
    w = c.welcome[0]
    assert w["auth"] == "hmac-sha256", w
    assert c.request(lambda id: op.auth(id, "alice", op.auth_mac(TOKEN.encode(), w["nonce"], "alice")))["type"] == "ok"
    job = c.submit(small_cornell(width=32, height=32), name="tls", halt_=op.halt(spp=2))["job"]
    wait_state(c, job, {"done"})
    img = c.job("fetch", job)
    assert img["type"] == "image" and len(img["_payload"]) > 1000, img
    # Plain bytes on the TLS port: the handshake fails and the connection is closed.
    p = op.Client(d.tcp, client_name=None)
    p.send(op.hello(1, "plain"))
    try:
        p.recv(timeout=5)
        raise AssertionError("a plaintext client got a frame from a TLS port")
    except (ConnectionError, OSError):
        pass
    d.wait_log(r"TLS failed: ")
    # Unix sockets stay plain.
    assert d.client().welcome[0]["auth"] == "peer"
    # The omega client over TLS: trusted with OMEGA_TLS_CA, refused without it.
    tls_addr = "tls:" + d.tcp[4:]
    env = dict(os.environ, OMEGA_USER="alice", OMEGA_TOKEN=TOKEN, OMEGA_TLS_CA=cert)
    r = subprocess.run([harness.OMEGA, "list", "--host", tls_addr], env=env, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "alice" in r.stdout, (r.stdout, r.stderr)
    env.pop("OMEGA_TLS_CA")
    r = subprocess.run([harness.OMEGA, "list", "--host", tls_addr], env=env, capture_output=True, text=True, timeout=60)
    assert r.returncode == 3 and "certificate not trusted" in r.stderr, (r.returncode, r.stderr)


def test_bad_key_refused(tmp, daemons):
    cert, _ = make_cert(tmp)
    bad = os.path.join(tmp, "bad.pem")
    open(bad, "w").write("not a key\n")
    cfg = os.path.join(tmp, "c.yaml")
    open(cfg, "w").write(f"tls_cert: {cert}\ntls_key: {bad}\n")
    r = subprocess.run([OMEGAD, "--config", cfg, "--state-dir", os.path.join(tmp, "s"), "--listen",
                        "tcp:127.0.0.1:0"], capture_output=True, text=True, timeout=30)
    assert r.returncode != 0 and "tls_key" in r.stderr, r.stderr


if __name__ == "__main__":
    t = Test()
    t.run(test_tls_session)
    t.run(test_bad_key_refused)
    t.exit()
