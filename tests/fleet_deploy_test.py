#!/usr/bin/python3
"""The deployment files of a fleet (docs/fleet.md), checked offline.

The Kubernetes manifests (deploy/kubernetes/) parsed, with the fields a fleet depends on present:
one volume per daemon, probes, resources, disruption budgets, the nightly CronJob; the proxy's
ConfigMap exactly what deploy/nginx/render.py makes for the StatefulSet's daemons, and accepted by
`nginx -t`; the Envoy configuration's ring keyed on x-fremen-map alike for gRPC and HTTP; the
Dockerfile's stages, user and health check.

  fleet_deploy_test.py              the checks (unittest)
  fleet_deploy_test.py --kubectl    kubectl's client-side dry run of the manifests; exit 77 (ctest's
                                    SKIP_RETURN_CODE) when it cannot work offline
"""

import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
KUBE = os.path.join(ROOT, "deploy", "kubernetes")
RENDER = os.path.join(ROOT, "deploy", "nginx", "render.py")
NGINX = shutil.which("nginx") or ("/usr/sbin/nginx" if os.access("/usr/sbin/nginx", os.X_OK) else None)
SKIP = 77


def documents(name):
    with open(os.path.join(KUBE, name)) as f:
        return [d for d in yaml.safe_load_all(f) if d]


def all_documents():
    return [d for name in sorted(os.listdir(KUBE)) if name.endswith(".yaml") and name != "kustomization.yaml"
            for d in documents(name)]


def one(kind, name=None):
    found = [d for d in all_documents() if d["kind"] == kind and (name is None or d["metadata"]["name"] == name)]
    assert len(found) == 1, f"{len(found)} {kind} {name or ''}"
    return found[0]


def render(*args):
    return subprocess.run([sys.executable, RENDER, *args], capture_output=True, text=True, check=False)


def nginx_test(config_text, directory):
    path = os.path.join(directory, "nginx.conf")
    with open(path, "w") as f:
        f.write(config_text)
    return subprocess.run([NGINX, "-t", "-p", directory, "-c", path, "-e", os.path.join(directory, "error.log")],
                          capture_output=True, text=True, check=False)


def statefulset_daemons():
    """The placement's names of the StatefulSet's daemons: its per-pod Services' names, port 50051."""
    sts = one("StatefulSet", "fremend")
    return [f"fremend-{i}" for i in range(sts["spec"]["replicas"])]


class KubernetesManifestsTest(unittest.TestCase):
    def test_every_manifest_is_listed_in_the_kustomization(self):
        with open(os.path.join(KUBE, "kustomization.yaml")) as f:
            listed = set(yaml.safe_load(f)["resources"])
        on_disk = {n for n in os.listdir(KUBE) if n.endswith(".yaml") and n != "kustomization.yaml"}
        self.assertEqual(listed, on_disk)

    def test_the_statefulset_gives_each_daemon_a_volume_probes_and_resources(self):
        sts = one("StatefulSet", "fremend")
        spec = sts["spec"]
        self.assertGreaterEqual(spec["replicas"], 2)
        claims = spec["volumeClaimTemplates"]
        self.assertEqual(len(claims), 1)
        self.assertIn("storage", claims[0]["spec"]["resources"]["requests"])
        self.assertEqual(claims[0]["spec"]["accessModes"], ["ReadWriteOnce"])
        pod = spec["template"]["spec"]
        self.assertTrue(pod["securityContext"]["runAsNonRoot"])
        (container,) = pod["containers"]
        mounts = {m["name"]: m["mountPath"] for m in container["volumeMounts"]}
        self.assertEqual(mounts[claims[0]["metadata"]["name"]], "/var/lib/fremen")
        self.assertIn("--data-dir=/var/lib/fremen", container["args"])
        self.assertEqual(container["startupProbe"]["grpc"]["port"], 50051)
        self.assertEqual(container["readinessProbe"]["httpGet"]["path"], "/readyz")
        self.assertEqual(container["livenessProbe"]["httpGet"]["path"], "/healthz")
        for key in ("cpu", "memory"):
            self.assertIn(key, container["resources"]["requests"])
        self.assertIn("memory", container["resources"]["limits"])
        ports = {p["name"]: p["containerPort"] for p in container["ports"]}
        self.assertEqual(ports, {"grpc": 50051, "http": 50052})

    def test_the_headless_service_and_one_service_per_daemon(self):
        sts = one("StatefulSet", "fremend")
        headless = one("Service", sts["spec"]["serviceName"])
        self.assertEqual(headless["spec"]["clusterIP"], "None")
        pod_labels = sts["spec"]["template"]["metadata"]["labels"]
        for name in statefulset_daemons():
            service = one("Service", name)
            selector = service["spec"]["selector"]
            self.assertEqual(selector["statefulset.kubernetes.io/pod-name"], name)
            for key, value in selector.items():
                if key != "statefulset.kubernetes.io/pod-name":
                    self.assertEqual(pod_labels[key], value)
            self.assertEqual({p["port"] for p in service["spec"]["ports"]}, {50051, 50052})

    def test_disruption_budgets_cover_the_daemons_and_the_proxy(self):
        budgets = {d["metadata"]["name"]: d for d in all_documents() if d["kind"] == "PodDisruptionBudget"}
        self.assertEqual(budgets["fremend"]["spec"]["maxUnavailable"], 1)
        self.assertEqual(budgets["fremen-proxy"]["spec"]["maxUnavailable"], 1)
        for name, owner in (("fremend", one("StatefulSet", "fremend")), ("fremen-proxy", one("Deployment"))):
            labels = owner["spec"]["template"]["metadata"]["labels"]
            for key, value in budgets[name]["spec"]["selector"]["matchLabels"].items():
                self.assertEqual(labels[key], value)

    def test_the_proxy_mounts_its_configmap_and_has_probes_and_resources(self):
        deployment = one("Deployment", "fremen-proxy")
        pod = deployment["spec"]["template"]["spec"]
        (container,) = pod["containers"]
        volumes = {v["name"]: v for v in pod["volumes"]}
        mounts = {m["name"]: m["mountPath"] for m in container["volumeMounts"]}
        config_volume = next(n for n, v in volumes.items() if "configMap" in v)
        self.assertEqual(volumes[config_volume]["configMap"]["name"], one("ConfigMap")["metadata"]["name"])
        self.assertIn(mounts[config_volume] + "/nginx.conf", container["args"])
        self.assertIn("readinessProbe", container)
        self.assertIn("livenessProbe", container)
        self.assertIn("cpu", container["resources"]["requests"])
        self.assertGreaterEqual(deployment["spec"]["replicas"], 2)

    def test_the_cronjob_updates_every_map_of_every_daemon_nightly(self):
        cron = one("CronJob", "fremen-update")
        fields = cron["spec"]["schedule"].split()
        self.assertEqual(len(fields), 5, cron["spec"]["schedule"])
        for field in fields:
            self.assertRegex(field, r"^[0-9*/,-]+$")
        self.assertEqual(cron["spec"]["concurrencyPolicy"], "Forbid")
        (container,) = cron["spec"]["jobTemplate"]["spec"]["template"]["spec"]["containers"]
        command = container["command"] + container["args"]
        self.assertEqual(command[:4], ["fremenctl", "update", "--all", "--wait"])
        address = next(a for a in command if a.startswith("--address="))[len("--address="):]
        # Every pod: through the headless Service (which publishes pods not yet ready too).
        headless = one("Service", one("StatefulSet")["spec"]["serviceName"])
        self.assertEqual(address, f"all:{headless['metadata']['name']}:50051")
        self.assertTrue(headless["spec"]["publishNotReadyAddresses"])
        # The daemons' own schedules are off, or each map would be updated twice a night.
        sts_container = one("StatefulSet")["spec"]["template"]["spec"]["containers"][0]
        self.assertIn("--update-schedule=", sts_container["args"])


class ProxyConfigTest(unittest.TestCase):
    def test_the_configmap_is_what_render_makes_for_the_statefulsets_daemons(self):
        args = ["--configmap", "fremen-proxy"]
        for d in statefulset_daemons():
            args += ["--daemon", f"{d}:50051={d}:50052"]
        rendered = render(*args)
        self.assertEqual(rendered.returncode, 0, rendered.stderr)
        with open(os.path.join(KUBE, "proxy-configmap.yaml")) as f:
            self.assertEqual(f.read(), rendered.stdout, "re-render deploy/kubernetes/proxy-configmap.yaml")
        conf = one("ConfigMap", "fremen-proxy")["data"]["nginx.conf"]
        self.assertIn("hash $http_x_fremen_map consistent;", conf)
        self.assertIn("grpc_pass grpc://fremend;", conf)
        servers = re.findall(r"upstream fremend \{(.*?)\}", conf, re.S)[0]
        self.assertEqual(re.findall(r"server (\S+) max_fails=0;", servers),
                         [f"{d}:50051" for d in statefulset_daemons()])

    @unittest.skipIf(NGINX is None, "nginx is not installed (scripts/install-deps.sh installs nginx-light)")
    def test_nginx_accepts_a_loopback_fleet_and_the_configmap(self):
        with tempfile.TemporaryDirectory() as tmp:
            rendered = render("--runtime-dir", tmp, "--grpc-listen", "127.0.0.1:50081",
                              "--http-listen", "127.0.0.1:50082", "--daemon", "127.0.0.1:50051=127.0.0.1:50052",
                              "--daemon", "127.0.0.1:50061=127.0.0.1:50062")
            self.assertEqual(rendered.returncode, 0, rendered.stderr)
            checked = nginx_test(rendered.stdout, tmp)
            self.assertEqual(checked.returncode, 0, checked.stderr)
            self.assertIn("test is successful", checked.stderr)
        with tempfile.TemporaryDirectory() as tmp:
            # The cluster's names do not resolve here: the same text with loopback addresses (nginx -t
            # binds no port), and the container's /tmp moved into the test's directory.
            conf = one("ConfigMap", "fremen-proxy")["data"]["nginx.conf"]
            conf = re.sub(r"\bfremend-(\d+):", lambda m: f"127.0.0.{int(m.group(1)) + 1}:", conf)
            conf = conf.replace(" /tmp/", f" {tmp}/").replace("0.0.0.0:", "127.0.0.1:")
            checked = nginx_test(conf, tmp)
            self.assertEqual(checked.returncode, 0, checked.stderr)

    def test_render_refuses_what_would_not_route(self):
        self.assertEqual(render().returncode, 2)
        self.assertIn("twice", render("--daemon", "a:1=a:2", "--daemon", "a:1=a:2").stderr)
        self.assertIn("every daemon an HTTP address", render("--daemon", "a:1=a:2", "--daemon", "b:1").stderr)
        # Named daemons whose ports differ: nginx sees only the owner's IP, no pattern can map it.
        self.assertIn("same two ports", render("--daemon", "a:1=a:2", "--daemon", "b:3=b:4").stderr)
        self.assertIn("HOST:PORT", render("--daemon", "nohost").stderr)


class EnvoyConfigTest(unittest.TestCase):
    def setUp(self):
        with open(os.path.join(ROOT, "deploy", "envoy", "envoy.yaml")) as f:
            self.config = yaml.safe_load(f)
        self.clusters = {c["name"]: c for c in self.config["static_resources"]["clusters"]}

    def hash_keys(self, cluster):
        return [e["metadata"]["filter_metadata"]["envoy.lb"]["hash_key"]
                for group in self.clusters[cluster]["load_assignment"]["endpoints"] for e in group["lb_endpoints"]]

    def test_both_rings_hash_the_same_daemons_without_failover(self):
        for name in ("fremend_grpc", "fremend_http"):
            cluster = self.clusters[name]
            self.assertEqual(cluster["lb_policy"], "RING_HASH")
            for failover in ("health_checks", "outlier_detection"):
                self.assertNotIn(failover, cluster)
        self.assertEqual(self.hash_keys("fremend_grpc"), self.hash_keys("fremend_http"))
        self.assertEqual(self.hash_keys("fremend_grpc"), statefulset_daemons())

    def test_routes_hash_on_the_map(self):
        listeners = {x["name"]: x for x in self.config["static_resources"]["listeners"]}
        for name, cluster in (("grpc", "fremend_grpc"), ("http", "fremend_http")):
            manager = listeners[name]["filter_chains"][0]["filters"][0]["typed_config"]
            routes = manager["route_config"]["virtual_hosts"][0]["routes"]
            hashed = [r for r in routes if r["route"]["cluster"] == cluster]
            self.assertTrue(hashed)
            self.assertEqual(hashed[0]["route"]["hash_policy"][0]["header"]["header_name"], "x-fremen-map")
            for route in hashed:
                self.assertIn("hash_policy", route["route"])
            self.assertNotIn("retry_policy", str(routes))


class DockerfileTest(unittest.TestCase):
    def test_two_debian_stages_a_non_root_user_and_a_health_check(self):
        with open(os.path.join(ROOT, "deploy", "Dockerfile")) as f:
            lines = [line.strip() for line in f if line.strip() and not line.lstrip().startswith("#")]
        stages = [line for line in lines if line.startswith("FROM ")]
        self.assertEqual(len(stages), 2)
        for stage in stages:
            self.assertRegex(stage, r"^FROM debian:12\b")
        users = [line.split()[1] for line in lines if line.startswith("USER ")]
        self.assertTrue(users)
        self.assertNotIn(users[-1].split(":")[0], ("root", "0"))
        self.assertTrue(any(line.startswith("HEALTHCHECK ") for line in lines))
        self.assertTrue(any(line.startswith("ENTRYPOINT") and "fremend" in line for line in lines))
        # Portable: the image's build takes the repository's portable default, never -march=native.
        self.assertTrue(any(line.startswith("ARG FREMEN_MARCH=") and "native" not in line for line in lines))

    def test_the_build_stage_installs_every_library_the_build_needs(self):
        # Every -dev package (and the embedded Chart.js) that scripts/install-deps.sh installs for the
        # build: CMake's configure needs them all, and one missing breaks only the image's build.
        with open(os.path.join(ROOT, "scripts", "install-deps.sh")) as f:
            listed = re.search(r"^packages=\((.*?)^\)", f.read(), re.S | re.M).group(1)
        words = [w for line in listed.splitlines() for w in line.split("#")[0].split()]
        needed = [w for w in words if w.endswith("-dev") or w == "libjs-chart.js"]
        self.assertIn("libpng-dev", needed)
        with open(os.path.join(ROOT, "deploy", "Dockerfile")) as f:
            build_stage = f.read().split("FROM ")[1]
        installed = set(re.findall(r"[a-z0-9][a-z0-9.+-]+", build_stage))
        self.assertEqual([p for p in needed if p not in installed], [])


def kubectl_dry_run():
    kubectl = shutil.which("kubectl")
    if kubectl is None:
        print("SKIP: kubectl is not installed (Debian's kubernetes-client)")
        return SKIP
    built = subprocess.run([kubectl, "kustomize", KUBE], capture_output=True, text=True, check=False, timeout=120)
    if built.returncode != 0:
        print(built.stderr)
        return 1
    run = subprocess.run([kubectl, "apply", "--dry-run=client", "--validate=false", "--request-timeout=5s",
                          "-k", KUBE], capture_output=True, text=True, check=False, timeout=120)
    if run.returncode == 0:
        print(run.stdout)
        return 0
    if re.search(r"connection refused|no such host|couldn't get current server API|openapi|dial tcp", run.stderr):
        print("SKIP: kubectl's client-side dry run needs an API server to map the kinds (none here); "
              "`kubectl kustomize` built the manifests offline:\n" + run.stderr.strip().splitlines()[-1])
        return SKIP
    print(run.stderr)
    return 1


if __name__ == "__main__":
    if sys.argv[1:] == ["--kubectl"]:
        sys.exit(kubectl_dry_run())
    unittest.main(verbosity=2)
