"""Sweeps: a chapter's seeds and set-ups as tasks of a Dask cluster, merged as one run.

A task is one seed's whole node graph (the chapter's ``run.sh`` with an override naming the
seed, in its own ROS domain, claimed through a lock file, and its own run directory) or one
in-process run (``python -m lpa_transfer.inverse_dynamics.in_process run``, one set-up and
seed). Tasks run as subprocesses of the workers, a worker thread a task slot: a local cluster
of one slot per core, or a running cluster at ``--address``. A task that fails runs once more;
one that fails twice is named and the sweep exits 1 without merging. Otherwise the chapter's
merge joins the tasks' results into the outputs of one run over all the seeds (docs/library.md,
"Sweeps").

Usage (``python -m lpa_transfer.sweeps``, from the repository root)::

    graph ch5|ch6 [--seeds N ...] [--config FILE] [--override FILE]... [--out DIR]
    inprocess [--setups S ...] [--seeds N ...] [--trials T] [--out DIR]
    common options: [--address tcp://HOST:PORT [--min-workers N] | --workers N]
                    [--domains FIRST-LAST]

The module imports no ROS package and Dask only when a sweep starts.
"""
import argparse
import fcntl
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
#: chapter -> (run.sh, merge script, default configuration, default output directory)
GRAPH_CHAPTERS = {   # the run directory's marker is ".<scenario folder>_run" (graph.sh)
    "ch5": ("scenarios/inverse_dynamics/run.sh", "scenarios/inverse_dynamics/merge_results.py",
            "scenarios/inverse_dynamics/config.yaml", "runs/inverse_dynamics"),
    "ch6": ("scenarios/goal_babbling/run.sh", "scenarios/goal_babbling/merge_results.py",
            "scenarios/goal_babbling/config.yaml", "runs/goal_babbling"),
}
#: the files of a graph task's run directory that its merge reads (sent back to the head)
GRAPH_RESULTS = ("results.json", "learning_curves.csv")
DOMAINS = tuple(range(150, 200))
MARKER = ".sweep_run"
#: how often a progress line is printed while no task ends
PROGRESS_SECONDS = 60.0


class TaskFailed(RuntimeError):
    """A task's command exited non-zero (the message ends with the end of its log)."""


@dataclass(frozen=True)
class Task:
    """One unit of a sweep: ``argv`` run from the repository root, after ``inputs`` (name ->
    text) are written into ``inputs_dir``; ``run_dir`` is its run directory, ``results`` the
    files in it returned to the head; ``ros``: the command needs its own ROS domain."""
    name: str
    argv: tuple
    run_dir: str
    log: str
    results: tuple = ()
    inputs: dict = field(default_factory=dict)
    inputs_dir: str = ""
    ros: bool = False


def _claim_domain(domains):
    """(domain id, open lock file) of the first of ``domains`` that no other task of this
    machine holds (waiting for one to come free); the claim lasts while the file is open."""
    locks = Path(tempfile.gettempdir()) / "lpa_sweep_domains"
    locks.mkdir(exist_ok=True)
    while True:
        for domain in domains:
            handle = open(locks / f"{domain}.lock", "w")
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                handle.close()
                continue
            return domain, handle
        time.sleep(1.0)


def _die_with_parent():
    """The task's command gets SIGTERM if its worker dies (run.sh then stops its nodes)."""
    import ctypes
    ctypes.CDLL(None).prctl(1, signal.SIGTERM)   # PR_SET_PDEATHSIG


def run_task(task, domains=DOMAINS):
    """Run ``task`` here (on a worker): {'worker', 'seconds', 'domain', 'files'}, the files
    being ``task.results`` read from its run directory; raises TaskFailed."""
    start = time.monotonic()
    if task.inputs:
        Path(task.inputs_dir).mkdir(parents=True, exist_ok=True)
        for name, text in task.inputs.items():
            (Path(task.inputs_dir) / name).write_text(text)
    env = dict(os.environ, PYTHONUNBUFFERED="1", ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    domain, lock = (None, None)
    if task.ros:
        domain, lock = _claim_domain(domains)
        env["ROS_DOMAIN_ID"] = str(domain)
    Path(task.log).parent.mkdir(parents=True, exist_ok=True)
    try:
        with open(task.log, "wb") as log:
            argv = [sys.executable if a == "python" else a for a in task.argv]
            code = subprocess.run(argv, cwd=ROOT, env=env, stdout=log,
                                  stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                  preexec_fn=_die_with_parent).returncode
    finally:
        if lock:
            lock.close()
    where = _worker_address()
    if code != 0:
        tail = Path(task.log).read_text(errors="replace").splitlines()[-8:]
        raise TaskFailed(f"exit {code} on {where} (log {task.log}); it ends with:\n  "
                         + "\n  ".join(tail))
    files = {name: (Path(task.run_dir) / name).read_bytes() for name in task.results
             if (Path(task.run_dir) / name).exists()}
    return {"worker": where, "seconds": time.monotonic() - start, "domain": domain,
            "files": files}


def _worker_address():
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return "this process"


def _say(text):
    print(text, flush=True)


def _minutes(seconds):
    return f"{seconds / 60:.0f}" if seconds >= 600 else f"{seconds / 60:.1f}"


class Progress:
    """'k/N tasks done, ~M min left'. The time left is the work left over the task slots:
    the mean task time so far for each queued task, and what the mean leaves of each running
    one, modelled as started when its slot came free (tasks start in order, a slot at a time)."""

    def __init__(self, total, slots):
        self.total, self.slots = total, max(1, slots)
        self.start = time.monotonic()
        self.durations = []
        self.running = [self.start] * min(self.slots, total)   # modelled start times
        self.queued = total - len(self.running)

    def ended(self, seconds=None, again=False):
        """A task ended (``seconds``: its time when it succeeded; ``again``: it runs again)."""
        now = time.monotonic()
        if self.running:
            self.running.pop(0)
        if seconds is not None:
            self.durations.append(seconds)
        self.queued += bool(again)
        if self.queued:
            self.queued -= 1
            self.running.append(now)

    def line(self, done):
        now = time.monotonic()
        elapsed = _minutes(now - self.start)
        if not self.durations:
            return (f"{done}/{self.total} tasks done, {elapsed} min so far "
                    "(time left: once a task has ended)")
        mean = sum(self.durations) / len(self.durations)
        work = self.queued * mean + sum(max(mean - (now - t), 0.0) for t in self.running)
        return (f"{done}/{self.total} tasks done, ~{_minutes(work / self.slots)} min left "
                f"({elapsed} min so far)")


def connect(address=None, workers=None, min_workers=0):
    """(client, cluster or None): the cluster at ``address`` (once ``min_workers`` workers
    have joined it), or a local one with ``workers`` task slots (default: this machine's
    cores), one thread each in this process (tasks are subprocesses)."""
    from distributed import Client, LocalCluster
    if address:
        client = Client(address, timeout="30s")
        if min_workers:
            client.wait_for_workers(min_workers, timeout=120)
        return client, None
    slots = workers or len(os.sched_getaffinity(0))
    cluster = LocalCluster(n_workers=slots, threads_per_worker=1, processes=False,
                           dashboard_address=None)
    return Client(cluster), cluster


def run_sweep(tasks, client, domains=DOMAINS, say=_say, retries=1):
    """Run ``tasks`` on ``client``'s cluster: ({task name: result of run_task}, [(name,
    error text)] of the tasks that failed ``retries`` + 1 times)."""
    from distributed import wait
    slots = sum(client.nthreads().values())
    say(f"sweep: {len(tasks)} tasks on {slots} task slots "
        f"({len(client.nthreads())} workers at {client.scheduler.address})")
    progress = Progress(len(tasks), slots)
    pending = {}
    for priority, task in enumerate(tasks):
        future = client.submit(run_task, task, domains, pure=False, priority=-priority,
                               key=f"{task.name} #1")
        pending[future] = (task, 1)
    results, failed = {}, []
    say(progress.line(0))
    while pending:
        try:
            finished = wait(list(pending), timeout=PROGRESS_SECONDS,
                            return_when="FIRST_COMPLETED").done
        except TimeoutError:
            say(progress.line(len(results) + len(failed)))
            continue
        for future in finished:
            task, attempt = pending.pop(future)
            try:
                result = future.result()
            except Exception as error:   # the task's own failure, or its worker's  # noqa: BLE001
                text = f"{type(error).__name__}: {error}"
                if attempt <= retries:
                    say(f"task {task.name} failed ({text.splitlines()[0]}): running it again")
                    again = client.submit(run_task, task, domains, pure=False,
                                          key=f"{task.name} #{attempt + 1}")
                    pending[again] = (task, attempt + 1)
                    progress.ended(again=True)
                    continue
                failed.append((task.name, text))
                progress.ended()
                say(f"task {task.name} failed again: {text}")
            else:
                results[task.name] = result
                progress.ended(result["seconds"])
                say(f"task {task.name} done on {result['worker']} in "
                    f"{result['seconds']:.0f} s")
            say(progress.line(len(results) + len(failed)))
    return results, failed


def prepare_out(out, scenario=None):
    """Make ``out`` a new sweep's output directory: an earlier sweep's, or a run directory of
    the chapter's run.sh (``scenario``), is cleared; a directory of something else is refused.
    It is marked as both, so that run.sh may clear it in turn."""
    out = Path(out).resolve()
    markers = [MARKER] + ([f".{scenario}_run"] if scenario else [])
    if out.is_dir() and any(out.iterdir()):
        if not any((out / marker).exists() for marker in markers):
            raise SystemExit(f"error: {out} exists and is not a sweep's output directory")
        shutil.rmtree(out)
    out.mkdir(parents=True, exist_ok=True)
    for marker in markers:
        (out / marker).touch()
    return out


def experiment_list(key, configs):
    """A list parameter of the experiment node: the last of ``configs`` that sets it wins."""
    value = None
    for path in configs:
        value = ((yaml.safe_load(Path(path).read_text()) or {}).get("experiment") or {}).get(
            "ros__parameters", {}).get(key, value)
    return value


def graph_tasks(chapter, out, seeds=None, config=None, overrides=()):
    """One task per seed: the chapter's run.sh over the configuration with the overrides and
    one naming the seed (the files travel with the task), into ``out/tasks/seed<N>``."""
    script, _, default_config, _ = GRAPH_CHAPTERS[chapter]
    configs = [Path(config or ROOT / default_config)] + [Path(o) for o in overrides]
    if seeds is None:
        seeds = experiment_list("seeds", configs)
    tasks = []
    for seed in seeds:
        inputs_dir = out / "tasks" / f"seed{seed}.inputs"
        inputs = {f"{k}_{path.name}": path.read_text() for k, path in enumerate(configs)}
        inputs["seed.yaml"] = f"experiment:\n  ros__parameters:\n    seeds: [{int(seed)}]\n"
        files = [str(inputs_dir / name) for name in inputs]
        argv = ["bash", script, "--config", files[0]]
        for name in files[1:]:
            argv += ["--override", name]
        run_dir = out / "tasks" / f"seed{seed}"
        tasks.append(Task(f"{chapter} seed {seed}", tuple(argv + ["--out", str(run_dir)]),
                          str(run_dir), str(out / "tasks" / f"seed{seed}.log"), GRAPH_RESULTS,
                          inputs, str(inputs_dir), ros=True))
    return tasks


def _write_results(tasks, results):
    """Each task's returned files into its run directory on this machine (the head)."""
    for task in tasks:
        for name, data in results[task.name]["files"].items():
            path = Path(task.run_dir) / name
            path.parent.mkdir(parents=True, exist_ok=True)
            if not path.exists() or path.read_bytes() != data:
                path.write_bytes(data)


def merge_graph(chapter, out, tasks, results, say=_say):
    """Write each task's results on this machine and join them with the chapter's merge."""
    _write_results(tasks, results)
    merge = GRAPH_CHAPTERS[chapter][1]
    done = subprocess.run([sys.executable, merge, str(out)] + [t.run_dir for t in tasks],
                          cwd=ROOT, capture_output=True, text=True)
    (out / "merge.log").write_text(done.stdout + done.stderr)
    if done.returncode != 0:
        say(f"error: {merge} failed:\n{done.stderr.strip()}")
        return 1
    say(done.stdout.rstrip())
    say(f"merged {len(tasks)} tasks into {out} (each task's run directory: {out}/tasks/)")
    return 0


#: The in-process experiment's module, run by the in-process tasks and merge.
IN_PROCESS = "lpa_transfer.inverse_dynamics.in_process"


def inprocess_tasks(out, setups, seeds, trials):
    """One task per set-up and seed: ``in_process run`` into ``out/tasks``."""
    tasks = []
    for setup in setups:
        for seed in seeds:
            argv = ("python", "-m", IN_PROCESS, "run", "--setup", setup,
                    "--seed", str(seed), "--trials", str(trials), "--out", str(out / "tasks"))
            run_dir = out / "tasks" / setup
            tasks.append(Task(f"{setup} seed {seed}", argv, str(run_dir),
                              str(out / "tasks" / f"{setup}_seed{seed}.log"),
                              (f"seed_{seed}.json",)))
    return tasks


def merge_inprocess(out, setups, tasks, results, say=_say):
    """The tasks' seed files on this machine, then ``export`` per set-up (``out/<setup>/``, a
    chapter 5 run directory) and ``report`` over the set-ups (``out/report.txt``)."""
    _write_results(tasks, results)
    in_process = [sys.executable, "-m", IN_PROCESS]
    for setup in setups:
        done = subprocess.run(in_process + ["export", "--setup", setup, "--to",
                                            str(out / setup), "--out", str(out / "tasks")],
                              cwd=ROOT, capture_output=True, text=True)
        if done.returncode != 0:
            say(f"error: exporting {setup} failed:\n{done.stderr.strip()}")
            return 1
    done = subprocess.run(in_process + ["report", "--out", str(out / "tasks"),
                                        "--setups", *setups],
                          cwd=ROOT, capture_output=True, text=True)
    (out / "report.txt").write_text(done.stdout)
    if done.returncode != 0:
        say(f"error: the report failed:\n{done.stderr.strip()}")
        return 1
    say(f"merged {len(tasks)} tasks into {out} (report.txt, one directory per set-up)")
    return 0


def _domains(text):
    """'150-199' or '3,17,40' -> the domain ids."""
    domains = []
    for part in text.split(","):
        first, _, last = part.partition("-")
        domains += range(int(first), int(last or first) + 1)
    if not domains or not all(0 <= d <= 232 for d in domains):
        raise argparse.ArgumentTypeError("domains: FIRST-LAST or a comma list, within 0-232")
    return tuple(domains)


def command_line(argv=None):
    parser = argparse.ArgumentParser(prog="python -m lpa_transfer.sweeps",
                                     description=__doc__.split("\n")[0])
    common = argparse.ArgumentParser(add_help=False)
    where = common.add_mutually_exclusive_group()
    where.add_argument("--address", help="a running Dask scheduler (tcp://HOST:PORT)")
    where.add_argument("--workers", type=int, help="local task slots (default: the cores)")
    common.add_argument("--min-workers", type=int, default=0,
                        help="with --address: wait until this many workers have joined")
    common.add_argument("--domains", type=_domains, default=DOMAINS,
                        help="ROS domains a graph task may take on its machine (FIRST-LAST or A,B,...)")
    common.add_argument("--seeds", type=int, nargs="+")
    common.add_argument("--out", type=Path)
    verbs = parser.add_subparsers(dest="verb", required=True)
    graph = verbs.add_parser("graph", parents=[common], help="one task per seed's node graph")
    graph.add_argument("chapter", choices=sorted(GRAPH_CHAPTERS))
    graph.add_argument("--config", type=Path)
    graph.add_argument("--override", type=Path, action="append", default=[])
    inproc = verbs.add_parser("inprocess", parents=[common],
                              help="chapter 5 in process: one task per set-up and seed")
    inproc.add_argument("--setups", nargs="+", default=["today"])
    inproc.add_argument("--trials", type=int, default=15)
    args = parser.parse_args(argv)

    if args.verb == "graph":
        script = GRAPH_CHAPTERS[args.chapter][0]
        out = prepare_out(args.out or ROOT / GRAPH_CHAPTERS[args.chapter][3],
                          Path(script).parent.name)
        tasks = graph_tasks(args.chapter, out, args.seeds, args.config, args.override)
    else:
        out = prepare_out(args.out or ROOT / "runs" / "id_sweep")
        tasks = inprocess_tasks(out, args.setups, args.seeds or list(range(10)), args.trials)
    start = time.monotonic()
    client, cluster = connect(args.address, args.workers, args.min_workers)
    try:
        results, failed = run_sweep(tasks, client, args.domains)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    if failed:
        for name, text in failed:
            print(f"error: task {name} failed twice: {text.splitlines()[0]}", file=sys.stderr)
        return 1
    (out / "sweep.json").write_text(json.dumps(
        {"tasks": {name: {k: v for k, v in result.items() if k != "files"}
                   for name, result in results.items()},
         "wall_seconds": round(time.monotonic() - start, 1)}, indent=1) + "\n")
    if args.verb == "graph":
        code = merge_graph(args.chapter, out, tasks, results)
    else:
        code = merge_inprocess(out, args.setups, tasks, results)
    print(f"sweep: {len(tasks)} tasks in {time.monotonic() - start:.0f} s of wall time")
    return code


if __name__ == "__main__":
    # through the package's module, so that tasks reach the workers by reference
    from lpa_transfer import sweeps
    sys.exit(sweeps.command_line())
