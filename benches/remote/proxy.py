#!/usr/bin/env python3
"""The remote bench's link: a TCP proxy on loopback that delays every byte by 25 ms each
way and carries at most 50 MB/s in each direction (all connections together), as a
fast link to a far bucket does.

    python3 proxy.py UPSTREAM_PORT [--delay-ms 25] [--mbps 50]

prints its own port on stdout and forwards until killed. Order is kept: a chunk read at
time t leaves at t + delay, or later when the link is busy.
"""

import argparse
import asyncio
import socket
import sys
import time


class Link:
    """One direction's bandwidth, shared by every connection."""

    def __init__(self, bytes_per_s):
        self.rate = bytes_per_s
        self.free_at = 0.0

    def slot(self, n, ready):
        """When `n` bytes ready at `ready` have gone through the link."""
        start = max(ready, self.free_at)
        self.free_at = start + n / self.rate
        return self.free_at


async def pipe(reader, writer, link, delay):
    queue = asyncio.Queue()

    async def send():
        while True:
            item = await queue.get()
            if item is None:
                break
            due, data = item
            wait = due - time.monotonic()
            if wait > 0:
                await asyncio.sleep(wait)
            writer.write(data)
            await writer.drain()
        try:
            writer.write_eof()
        except (OSError, RuntimeError):
            pass

    sender = asyncio.ensure_future(send())
    try:
        while True:
            data = await reader.read(65536)
            if not data:
                break
            now = time.monotonic()
            await queue.put((link.slot(len(data), now + delay), data))
    except (ConnectionResetError, OSError):
        pass
    await queue.put(None)
    try:
        await sender
    except (ConnectionResetError, OSError):
        pass


async def main():
    p = argparse.ArgumentParser()
    p.add_argument("upstream", type=int)
    p.add_argument("--delay-ms", type=float, default=25.0)
    p.add_argument("--mbps", type=float, default=50.0)
    a = p.parse_args()
    delay = a.delay_ms / 1000.0
    up_link, down_link = Link(a.mbps * 1e6), Link(a.mbps * 1e6)

    async def handle(client_r, client_w):
        try:
            server_r, server_w = await asyncio.open_connection("127.0.0.1", a.upstream)
        except OSError:
            client_w.close()
            return
        for w in (client_w, server_w):
            w.get_extra_info("socket").setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        await asyncio.gather(
            pipe(client_r, server_w, up_link, delay),
            pipe(server_r, client_w, down_link, delay),
        )
        for w in (client_w, server_w):
            w.close()

    server = await asyncio.start_server(handle, "127.0.0.1", 0)
    print(server.sockets[0].getsockname()[1], flush=True)
    async with server:
        await server.serve_forever()


if __name__ == "__main__":
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        sys.exit(0)
