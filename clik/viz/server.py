"""A meshcat server on the loopback interface only, in a child process.

meshcat's own server (``python -m meshcat.servers.zmqserver``) prints
``http://127.0.0.1:7000`` but its HTTP and websocket server listens on every
interface (``0.0.0.0`` and ``[::]``): anyone on the network could watch, or
send commands through the browser's websocket. This module runs the same
bridge with both sockets bound to ``127.0.0.1`` on free ports chosen by the
system (port 0), and the child exits when its parent process is gone.

Run as a module it is the server (``python -m clik.viz.server --parent-pid N``,
it prints ``zmq_url=...`` and ``web_url=...``); :class:`MeshcatServer` starts one
and talks to it.
"""

from __future__ import annotations

import argparse
import atexit
import contextlib
import os
import queue
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from typing import Any

import zmq

from clik.errors import ClikError
from clik.viz.commands import Command, pack

LOOPBACK = "127.0.0.1"
"""The only address the server listens on."""

START_TIMEOUT_S = 20.0
"""Longest wait for the server to report its addresses [s]."""

REPLY_TIMEOUT_MS = 30_000
"""Longest wait for the server to acknowledge one command [ms]."""


class ServerError(ClikError, RuntimeError):
    """The meshcat server could not be started or stopped answering (exit code 4)."""

    exit_code = 4


class MeshcatServer:
    """A loopback-only meshcat server process and a ZMQ connection to it.

    Use :meth:`start`; the process is stopped by :meth:`stop`, at interpreter
    exit, and by itself when its parent process dies.

    Attributes:
        process: The server process.
        zmq_url: Where commands are sent (``tcp://127.0.0.1:<port>``).
        web_url: The viewer page (``http://127.0.0.1:<port>/static/``).
    """

    def __init__(self, process: subprocess.Popen[bytes], zmq_url: str, web_url: str) -> None:
        self.process = process
        self.zmq_url = zmq_url
        self.web_url = web_url
        self._context: zmq.Context[zmq.Socket[bytes]] = zmq.Context.instance()
        self._socket: Any = None
        self._connect()
        atexit.register(self.stop)

    @classmethod
    def start(cls, timeout: float = START_TIMEOUT_S) -> MeshcatServer:
        """Start a server process and wait for its addresses.

        Raises:
            ServerError: The process exited or did not answer within ``timeout`` [s].
        """
        args = [sys.executable, "-u", "-m", "clik.viz.server", "--parent-pid", str(os.getpid())]
        process = subprocess.Popen(
            args,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            stdin=subprocess.DEVNULL,
            start_new_session=True,
        )
        lines: queue.Queue[str] = queue.Queue()

        def read() -> None:
            assert process.stdout is not None
            for raw in process.stdout:
                lines.put(raw.decode("utf-8", "replace").strip())

        threading.Thread(target=read, daemon=True).start()
        found: dict[str, str] = {}
        deadline = time.monotonic() + timeout
        while len(found) < 2:
            remaining = deadline - time.monotonic()
            if remaining <= 0 or process.poll() is not None:
                _terminate(process)
                raise ServerError(f"the meshcat server did not start (exit code {process.poll()})")
            try:
                line = lines.get(timeout=min(remaining, 0.2))
            except queue.Empty:
                continue
            key, _, value = line.partition("=")
            if key in ("zmq_url", "web_url"):
                found[key] = value
        return cls(process, found["zmq_url"], found["web_url"])

    def _connect(self) -> None:
        if self._socket is not None:
            self._socket.close(linger=0)
        self._socket = self._context.socket(zmq.REQ)
        self._socket.setsockopt(zmq.RCVTIMEO, REPLY_TIMEOUT_MS)
        self._socket.setsockopt(zmq.SNDTIMEO, REPLY_TIMEOUT_MS)
        self._socket.setsockopt(zmq.LINGER, 0)
        self._socket.connect(self.zmq_url)

    @property
    def alive(self) -> bool:
        """True while the server process runs."""
        return self.process.poll() is None

    @property
    def pid(self) -> int:
        """Process id of the server."""
        return self.process.pid

    def send(self, command: Command) -> None:
        """Send one viewer command and wait for the server's acknowledgement.

        Raises:
            ServerError: The server did not acknowledge in time.
        """
        try:
            self._socket.send_multipart(
                [command["type"].encode(), command["path"].encode(), pack(command)]
            )
            self._socket.recv()
        except zmq.ZMQError as exc:
            self._connect()  # a REQ socket is unusable after a missed reply
            raise ServerError(
                f"the meshcat server at {self.zmq_url} did not answer: {exc}"
            ) from None

    def send_all(self, commands: Sequence[Command]) -> None:
        """Send commands in order."""
        for command in commands:
            self.send(command)

    def stop(self) -> None:
        """Stop the server process (idempotent)."""
        if self._socket is not None:
            self._socket.close(linger=0)
            self._socket = None
        _terminate(self.process)
        with contextlib.suppress(Exception):
            atexit.unregister(self.stop)

    def __repr__(self) -> str:
        state = "running" if self.alive else "stopped"
        return f"MeshcatServer({self.web_url!r}, pid={self.pid}, {state})"


def _terminate(process: subprocess.Popen[bytes]) -> None:
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
    if process.stdout is not None:
        with contextlib.suppress(Exception):
            process.stdout.close()


# --------------------------------------------------------------------------- server side


def _bridge() -> Any:
    """Meshcat's ZMQ-websocket bridge, listening on :data:`LOOPBACK` only, free ports.

    Two more changes: a browser that connects is sent the scene's objects
    before its animation (meshcat replays each node's animation with the node,
    the root first, so tracks would bind to objects not yet created), and
    ``/favicon.ico`` answers 204 instead of 404.
    """
    import tornado.httpserver
    import tornado.netutil
    import tornado.web
    from meshcat.servers.tree import walk
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class NoIcon(tornado.web.RequestHandler):
        def get(self) -> None:
            self.set_status(204)

    class LoopbackBridge(ZMQWebSocketBridge):
        bound_port = 0

        def send_scene(self, websocket: Any) -> None:
            animations = []
            for node in walk(self.tree):
                if node.object is not None:
                    websocket.write_message(node.object, binary=True)
                for p in node.properties:
                    websocket.write_message(p, binary=True)
                if node.transform is not None:
                    websocket.write_message(node.transform, binary=True)
                if node.animation is not None:
                    animations.append(node.animation)
            for animation in animations:
                websocket.write_message(animation, binary=True)

        def make_app(self) -> Any:
            app = super().make_app()
            app.add_handlers(r".*", [(r"/favicon\.ico", NoIcon)])

            def listen(port: int, **kwargs: Any) -> Any:
                sockets = tornado.netutil.bind_sockets(port, address=LOOPBACK)
                server = tornado.httpserver.HTTPServer(app, **kwargs)
                server.add_sockets(sockets)
                self.bound_port = sockets[0].getsockname()[1]
                return server

            app.listen = listen
            return app

    bridge = LoopbackBridge(zmq_url=f"tcp://{LOOPBACK}:*", host=LOOPBACK, port=0)
    bridge.zmq_url = bridge.zmq_socket.getsockopt_string(zmq.LAST_ENDPOINT)
    bridge.fileserver_port = bridge.bound_port
    bridge.web_url = f"http://{LOOPBACK}:{bridge.bound_port}/static/"
    return bridge


def main(argv: Sequence[str] | None = None) -> int:
    """Run the server until interrupted or until ``--parent-pid`` exits."""
    import tornado.ioloop

    parser = argparse.ArgumentParser(description="clik's loopback-only meshcat server")
    parser.add_argument(
        "--parent-pid", type=int, default=None, help="exit when this process is gone"
    )
    args = parser.parse_args(argv)
    bridge = _bridge()
    print(f"zmq_url={bridge.zmq_url}")
    print(f"web_url={bridge.web_url}", flush=True)
    # Nobody reads our output any more: do not let a full pipe block the server.
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    if args.parent_pid is not None:
        parent = args.parent_pid

        def check_parent() -> None:
            if os.getppid() != parent:
                tornado.ioloop.IOLoop.current().stop()

        tornado.ioloop.PeriodicCallback(check_parent, 1000).start()
    with contextlib.suppress(KeyboardInterrupt):
        bridge.run()
    return 0


if __name__ == "__main__":
    sys.exit(main())
