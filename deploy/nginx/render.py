#!/usr/bin/python3
"""Renders deploy/nginx/fremen.conf.template into an nginx.conf for a fleet of fremend daemons.

  render.py --daemon fremend-0.fremend:50051=fremend-0.fremend:50052 --daemon ... > nginx.conf

Each --daemon is GRPC[=HTTP]: the daemon's gRPC address, written exactly as the placement names
it (nginx hashes this string, port included: `fremenctl fleet placement --daemons` must be given
the same strings), and optionally its HTTP address (JSON API, dashboard, /metrics), which the
proxy's HTTP port then serves. Either every daemon has an HTTP address or none.

The HTTP side learns the owner's gRPC address as nginx resolved it (an IP:port) and needs that
daemon's HTTP address: literal IP daemons get one line each; daemons named by DNS need the same
host in both addresses and the same two ports on every daemon (a StatefulSet's pods), which a
single pattern then maps.

--configmap NAME wraps the configuration in a Kubernetes ConfigMap NAME (key nginx.conf), as
deploy/kubernetes/proxy-configmap.yaml is made:

  render.py --configmap fremen-proxy --daemon fremend-0:50051=fremend-0:50052 ... \
      > deploy/kubernetes/proxy-configmap.yaml

--runtime-dir DIR puts the pid file, error log, access log and temporary files in DIR (a test's
nginx, or any nginx run by a user that cannot write /var); without, they go to /tmp and the logs
to stderr and stdout (a container).
"""

import argparse
import ipaddress
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


class Daemon:
    def __init__(self, spec):
        grpc, _, http = spec.partition("=")
        self.grpc = grpc.strip()
        self.http = http.strip()
        if not re.fullmatch(r"[^\s:;{}]+:\d+", self.grpc):
            raise ValueError(f"--daemon {spec!r}: the gRPC address must be HOST:PORT")
        if self.http and not re.fullmatch(r"[^\s:;{}]+:\d+", self.http):
            raise ValueError(f"--daemon {spec!r}: the HTTP address must be HOST:PORT")

    @staticmethod
    def split(address):
        host, _, port = address.rpartition(":")
        return host, port


def is_ip(host):
    try:
        ipaddress.ip_address(host)
        return True
    except ValueError:
        return False


def http_of_grpc_lines(daemons):
    """The map body from an owner's resolved gRPC address to its HTTP address."""
    lines = []
    for d in daemons:
        if is_ip(Daemon.split(d.grpc)[0]):
            lines.append(f'        "{d.grpc}" {d.http};')
    named = [d for d in daemons if not is_ip(Daemon.split(d.grpc)[0])]
    if named:
        ports = {(Daemon.split(d.grpc)[1], Daemon.split(d.http)[1]) for d in named}
        same_host = all(Daemon.split(d.grpc)[0] == Daemon.split(d.http)[0] for d in named)
        if len(ports) != 1 or not same_host:
            raise ValueError("daemons named by DNS need the same host for gRPC and HTTP and the same two ports on "
                             "every daemon (nginx sees their resolved IP only)")
        grpc_port, http_port = ports.pop()
        lines.append(f'        "~^(?<fremen_owner_host>.+):{grpc_port}$" $fremen_owner_host:{http_port};')
    return "\n".join(lines)


def render(daemons, grpc_listen, http_listen, runtime_dir):
    if not daemons:
        raise ValueError("name at least one --daemon")
    names = [d.grpc for d in daemons]
    if len(set(names)) != len(names):
        raise ValueError("a daemon is listed twice")
    with_http = [d for d in daemons if d.http]
    if with_http and len(with_http) != len(daemons):
        raise ValueError("give every daemon an HTTP address, or none")
    serve_http = bool(with_http) and bool(http_listen)

    if runtime_dir:
        runtime_dir = os.path.abspath(runtime_dir)
        main = (f"pid {runtime_dir}/nginx.pid;\n"
                f"error_log {runtime_dir}/error.log info;\n"
                "worker_processes 1;")
        temp = runtime_dir
        access_log = f"{runtime_dir}/access.log"
    else:
        main = "pid /tmp/nginx.pid;\nerror_log stderr warn;\nworker_processes auto;"
        temp = "/tmp"
        access_log = "/dev/stdout"
    paths = "\n    ".join(f"{kind}_temp_path {temp}/{kind}_temp;"
                          for kind in ("client_body", "proxy", "fastcgi", "uwsgi", "scgi"))

    # max_fails=0: a daemon is never marked failed, so its maps never move to a neighbour (which
    # would answer NOT_FOUND for them) while it is down.
    grpc_servers = "\n".join(f"        server {d.grpc} max_fails=0;" for d in daemons)
    grpc_any = "\n".join(f"        server {d.grpc};" for d in daemons)
    with open(os.path.join(HERE, "fremen.conf.template")) as f:
        text = f.read()
    http_any = http_server = http_of_grpc = ""
    if serve_http:
        http_any = ("    upstream fremend_http_any {\n"
                    + "\n".join(f"        server {d.http};" for d in daemons)
                    + "\n        keepalive 16;\n    }\n")
        http_of_grpc = http_of_grpc_lines(daemons)
        with open(os.path.join(HERE, "http_server.template")) as f:
            http_server = f.read().replace("@HTTP_LISTEN@", http_listen)
    for key, value in (("@MAIN@", main), ("@HTTP_PATHS@", paths), ("@ACCESS_LOG@", access_log),
                       ("@GRPC_SERVERS@", grpc_servers), ("@GRPC_ANY_SERVERS@", grpc_any),
                       ("@HTTP_ANY_UPSTREAM@", http_any), ("@HTTP_OF_GRPC@", http_of_grpc),
                       ("@GRPC_LISTEN@", grpc_listen), ("@HTTP_SERVER@", http_server)):
        text = text.replace(key, value)
    return text


def configmap(name, text, command):
    """`text` as the key nginx.conf of a ConfigMap `name` (a YAML literal block)."""
    body = "".join(f"    {line}\n" if line else "\n" for line in text.splitlines())
    return (f"# Rendered by deploy/nginx/render.py; do not edit. Made with:\n#   {command}\n"
            f"apiVersion: v1\nkind: ConfigMap\nmetadata:\n  name: {name}\ndata:\n  nginx.conf: |\n{body}")


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--daemon", action="append", default=[], metavar="GRPC[=HTTP]",
                        help="a daemon: its gRPC address as the placement names it, and its HTTP address")
    parser.add_argument("--grpc-listen", default="0.0.0.0:50051", help="the proxy's gRPC address")
    parser.add_argument("--http-listen", default="0.0.0.0:50052",
                        help="the proxy's HTTP address (empty: none)")
    parser.add_argument("--runtime-dir", default="", help="pid, logs and temporary files here")
    parser.add_argument("--configmap", default="", metavar="NAME", help="as a Kubernetes ConfigMap NAME")
    parser.add_argument("--out", default="-", help="write here instead of stdout")
    args = parser.parse_args(argv)
    try:
        text = render([Daemon(s) for s in args.daemon], args.grpc_listen, args.http_listen, args.runtime_dir)
    except ValueError as e:
        print(f"render.py: {e}", file=sys.stderr)
        return 2
    if args.configmap:
        command = " ".join(["deploy/nginx/render.py", "--configmap", args.configmap]
                           + [f"--daemon {d}" for d in args.daemon])
        text = configmap(args.configmap, text, command)
    if args.out == "-":
        sys.stdout.write(text)
    else:
        with open(args.out, "w") as f:
            f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
