"""What a crash file's settings may name, and where: targets, robots, message folders.

A sidecar (validated by :mod:`fuzzer.artifacts.sidecar`) or a corpus manifest records the run
configuration. Nothing it names is imported or opened without the user's say-so:

* **targets**: only the builtins (``native``, ``python``) are taken from a
  file. A file naming any other ``module:attribute`` is refused unless the
  command line passes ``--targets`` (which then replaces the file's) or
  ``--trust-sidecar`` (the user vouches for the file).
* **robot**: a shipped robot by name, or a path to an existing regular file
  (relative paths are taken from the working directory, as recorded). Anything
  else (missing, a folder, a FIFO, a device) is refused; pass ``--robot``.
* **message paths** (``msg_path``): only existing folders; .msg files are parsed
  as data, never executed.
* **where**: a robot file or message folder a file names is read only inside the
  working directory or the file's own folder (symlinks followed, :func:`outside`).
  A path elsewhere (``/home/me/.ssh/...``, ``../../x``) is refused unread, not even
  tested for existence, unless the user passes it (``--robot``, ``--msg-path``) or
  vouches for the file (``--trust-sidecar``).
"""

from __future__ import annotations

import contextlib
import os
import re
import stat
from dataclasses import replace
from pathlib import Path
from typing import Any

from fuzzer.artifacts.sidecar import BUILTIN_TARGETS, SidecarError
from fuzzer.execution.session import RunConfig, unread_msg_path
from fuzzer.execution.tolerance import Tolerance
from robot_api import robots


def foreign_targets(targets: tuple[str, ...] | list[str]) -> list[str]:
    """The targets that are not builtins (importing them runs their code)."""
    from fuzzer.execution.targets import BUILTIN  # shipped aliases (ros_tf) import only shipped code

    return [t for t in targets if t not in BUILTIN_TARGETS and t not in BUILTIN]


def readable_folders(source: Path, folder: Path | None = None) -> tuple[Path, ...]:
    """Where a file's settings may point: ``folder`` (default: ``source``'s own folder) and
    the working directory."""
    out = [folder if folder is not None else source.parent]
    with contextlib.suppress(OSError):  # the working directory was removed
        out.append(Path.cwd())
    return tuple(out)


def outside(spec: str, folders: tuple[Path, ...]) -> bool:
    """Whether the path ``spec`` (relative to the working directory, symlinks followed) lies
    outside every one of ``folders``; a path that cannot be resolved counts as outside."""
    try:
        real = Path(os.path.realpath(spec))
        return not any(real.is_relative_to(os.path.realpath(f)) for f in folders)
    except (OSError, ValueError):
        return True


OPTIONS_OF = (
    "replay, minimize and a campaign take it; promote, export-bag, view and report take --robot "
    "(the campaign's file) and --trust-sidecar"
)
"""Where the options a refusal suggests (``--targets``, ``--robot``, ``--msg-path``) exist."""


def _refuse_outside(what: str, spec: str, source: Path, folders: tuple[Path, ...], option: str) -> None:
    if outside(spec, folders):
        where = " and ".join(dict.fromkeys(os.path.realpath(f) for f in folders))
        raise SidecarError(
            f"{source}: {what} {spec!r} leads outside {where} (symlinks followed), and a file's "
            f"settings are never followed elsewhere; pass {option} (the same path if you trust it; "
            f"{OPTIONS_OF}) or --trust-sidecar"
        )


def safe_robot(spec: str, source: Path, trust: bool = False, folder: Path | None = None) -> str:
    """A robot named by a file: a shipped name, or an existing regular file inside the working
    directory or ``folder`` (default: ``source``'s folder; anywhere with ``trust``).

    Raises
    ------
    SidecarError
        Naming ``source`` and what was chosen.
    """
    if spec in robots.known_robots():
        return spec
    if not trust:
        _refuse_outside("robot", spec, source, readable_folders(source, folder), "--robot NAME_OR_URDF")
    path = Path(spec)
    try:
        info = path.stat()
    except (OSError, ValueError):
        raise SidecarError(
            f"{source}: robot {spec!r} is neither a shipped robot nor an existing file; "
            f"pass --robot NAME_OR_URDF to choose one ({OPTIONS_OF})"
        ) from None
    if not stat.S_ISREG(info.st_mode):
        raise SidecarError(
            f"{source}: robot {spec!r} is not a regular file; pass --robot NAME_OR_URDF ({OPTIONS_OF})"
        )
    return spec


def sidecar_model(
    config: dict[str, Any],
    source: Path,
    trust: bool = False,
    robot: str | None = None,
    digest: object = None,
) -> tuple[Path, Any]:
    """The URDF and the twin's model of the robot a sidecar's ``config`` names (the default robot
    when it names none), for the commands that draw or export a crash (``export-bag``, ``view``).

    ``robot`` (``--robot``) replaces it, for a sidecar whose robot path was relative to another
    working folder; it must be the campaign's file when the sidecar records one (``digest``,
    its ``robot_sha256``).

    Raises
    ------
    SidecarError
        The robot is neither a shipped one nor a regular file where a file may point
        (:func:`safe_robot`; ``trust``: anywhere), or it no longer loads (a file changed or
        gone since, a tip link not in it), or ``robot`` is not the campaign's file.
    """
    import python_impl
    from robot_api.errors import RobotAPIError

    if robot is not None:
        check_given_robot(robot, digest, source)
    else:
        robot = safe_robot(config.get("robot", robots.DEFAULT_ROBOT), source, trust)
    try:
        urdf = robots.resolve(robot)
        return urdf, python_impl.RobotModel(urdf, config.get("tip_link"))
    except RobotAPIError as exc:
        raise SidecarError(
            f"{source}: its sidecar's robot {robot} does not load: {type(exc).__name__}: {exc}"
        ) from None


def check_given_robot(robot: str, digest: object, source: Path) -> None:
    """Refuse a ``--robot`` that is not the campaign's file: its SHA-256 against the sidecar's
    ``robot_sha256`` (``digest``, either case; when the sidecar records none, a warning says
    that nothing was checked).

    Raises
    ------
    SidecarError
        The file does not resolve, the sidecar's digest is no SHA-256, or the SHA-256 differs.
    """
    from fuzzer.artifacts.manifest import robot_digest

    mine = robot_digest(robot)
    if mine is None:
        raise SidecarError(f"--robot {robot}: neither a shipped robot nor a readable file")
    if digest is None or digest == "":
        from fuzzer.reporting import warn

        warn(f"{source}: its sidecar records no robot_sha256, so --robot {robot} is not checked")
        return
    if not isinstance(digest, str) or not re.fullmatch(r"[0-9a-fA-F]{64}", digest):
        raise SidecarError(f"{source}: its sidecar's robot_sha256 is not a SHA-256 (64 hex digits)")
    digest = digest.lower()
    if mine != digest:
        raise SidecarError(
            f"--robot {robot}: not the robot file {source}'s campaign ran on (its SHA-256 "
            f"{mine[:12]} differs from the sidecar's robot_sha256 {digest[:12]})"
        )


def config_from(data: dict[str, Any], source: Path, given: dict[str, Any], trust: bool = False) -> RunConfig:
    """The run configuration a validated sidecar (or manifest) records, with ``given`` on top.

    Parameters
    ----------
    data : dict
        A validated sidecar (``data["config"]`` is used).
    source : Path
        The file it came from (for messages).
    given : dict
        Options given on the command line; they replace the recorded ones.
    trust : bool
        ``--trust-sidecar``: import whatever targets the file names, and read its robot and
        message folders wherever they are.

    Raises
    ------
    SidecarError
        Foreign targets without ``--targets``/``--trust-sidecar``, or an unusable robot
        or message path.
    """
    config = data["config"]
    targets = tuple(config.get("targets", BUILTIN_TARGETS))
    if "targets" not in given and not trust:
        foreign = foreign_targets(targets)
        if foreign:
            modules = ", ".join(sorted({t.split(":", 1)[0] for t in foreign}))
            raise SidecarError(
                f"{source} names target {', '.join(foreign)} (module {modules}); code named by a file "
                "is never imported on its own. To run it, pass --trust-sidecar if you trust where the "
                f"file came from, or --targets {','.join(targets)}, or --targets native,python to "
                f"replay it on the builtins ({OPTIONS_OF})"
            )
    robot = config.get("robot", robots.DEFAULT_ROBOT)
    if "robot" not in given:
        robot = safe_robot(robot, source, trust)
    msg_path = tuple(config.get("msg_path", ()))
    if unread_msg_path(str(config.get("op", "move")), str(config.get("msg_type", "")), msg_path):
        msg_path = ()  # no folder it names could be read (a relative one broke replay elsewhere)
    if "msg_path" not in given:
        for root in msg_path:
            if not trust:
                _refuse_outside("msg_path", root, source, readable_folders(source), "--msg-path DIR")
            if not Path(root).is_dir():
                raise SidecarError(
                    f"{source}: msg_path {root!r} is not a folder; pass --msg-path ({OPTIONS_OF})"
                )
    tol = config.get("tolerance", {})
    recorded = RunConfig(
        op=config.get("op", "move"),
        robot=robot,
        tip_link=config.get("tip_link"),
        targets=(targets[0], targets[1]),
        tolerance=Tolerance(float(tol.get("m", 1e-6)), float(tol.get("rad", 1e-6))),
        msg_type=config.get("msg_type", ""),
        msg_path=msg_path,
        filtering=config.get("filtering", True),
        **({"max_steps": config["max_steps"]} if "max_steps" in config else {}),
    )
    fields = {k: v for k, v in given.items() if k in RunConfig.__dataclass_fields__}
    return replace(recorded, **fields) if fields else recorded


def describe(config: RunConfig) -> str:
    """One line naming a configuration (for messages)."""
    return (
        f"op {config.op}, robot {config.robot}, targets {','.join(config.targets)}, "
        f"{config.message_type}, tolerance {config.tolerance.metres:g} m / {config.tolerance.radians:g} rad"
    )
