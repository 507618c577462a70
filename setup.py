"""ament_python packaging of lpa_transfer (installed by tools/setup.sh with `pip install -e .`)."""
import ast
from pathlib import Path

from setuptools import find_packages, setup

PACKAGE = 'lpa_transfer'
HERE = Path(__file__).resolve().parent


def defines_main(path):
    return any(isinstance(node, ast.FunctionDef) and node.name == 'main'
               for node in ast.parse(path.read_text(), str(path)).body)


def node_scripts():
    """One console script per nodes/<name>.py that defines main(), so a new node needs no edit here."""
    return [f'{path.stem} = lpa_transfer_nodes.{path.stem}:main'
            for path in sorted(HERE.glob('nodes/*.py')) if defines_main(path)]


def share_files(folder):
    """data_files entries installing folder/ under share/lpa_transfer/folder/, tree preserved."""
    files = sorted(p.relative_to(HERE) for p in (HERE / folder).rglob('*')
                   if p.is_file() and '__pycache__' not in p.parts)
    dirs = sorted({f.parent for f in files})
    return [(f'share/{PACKAGE}/{d}', [str(f) for f in files if f.parent == d]) for d in dirs]


setup(
    name=PACKAGE,
    version='0.1.0',
    packages=find_packages(include=[PACKAGE, f'{PACKAGE}.*']) + ['lpa_transfer_nodes'],
    package_dir={'lpa_transfer_nodes': 'nodes'},
    data_files=[
        ('share/ament_index/resource_index/packages', [f'resource/{PACKAGE}']),
        (f'share/{PACKAGE}', ['package.xml']),
        *share_files('scenarios'),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='lpa_transfer maintainers',
    maintainer_email='maintainers@users.noreply.github.com',
    description='Local Procrustes Analysis transfer learning between robots',
    license='BSD-3-Clause',
    entry_points={'console_scripts': node_scripts()},
)
