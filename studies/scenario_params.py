"""A node's parameters as a scenario's run.sh gives them: ``--params-file`` yaml files, later
ones overriding earlier ones (the studies that rebuild a scenario's pieces in process)."""
from pathlib import Path

import yaml


def node_params(node, *files):
    """The ros__parameters of ``node`` in the yaml ``files`` (later ones override)."""
    params = {}
    for path in files:
        params.update((yaml.safe_load(Path(path).read_text()).get(node) or {})
                      .get("ros__parameters", {}))
    return params
