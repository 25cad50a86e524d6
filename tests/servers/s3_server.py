"""The tests' S3 server: moto's (from PyPI, `pip install "moto[server]"`), on 127.0.0.1
and a free port, with bucket BUCKET holding FOLDER's files under their relative paths.

    python3 s3_server.py BUCKET FOLDER

prints the port on stdout once the files are in, and serves until its stdin closes (the
test ends) or it is killed. Any access key is accepted (moto checks none).
"""

import os
import socket
import sys

import boto3
from moto.server import ThreadedMotoServer


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main():
    bucket, folder = sys.argv[1], sys.argv[2]
    port = free_port()
    server = ThreadedMotoServer(ip_address="127.0.0.1", port=port, verbose=False)
    server.start()
    s3 = boto3.client(
        "s3",
        endpoint_url="http://127.0.0.1:%d" % port,
        aws_access_key_id="test",
        aws_secret_access_key="test",
        region_name="us-east-1",
    )
    s3.create_bucket(Bucket=bucket)
    for root, _, files in os.walk(folder):
        for name in files:
            path = os.path.join(root, name)
            key = os.path.relpath(path, folder).replace(os.sep, "/")
            s3.upload_file(path, bucket, key)
    print(port, flush=True)
    sys.stdin.read()
    server.stop()


if __name__ == "__main__":
    main()
