"""The cryptography lesson's judgements (graders/cryptography.py declares the checks and their order).

The grader's own runs of the system's ``age`` and ``ssh-keygen`` (:func:`tool`, on private copies of the
files, never a program of the submission), the judgement of each group of checks as ``{check id: (passed,
observed)}`` (:func:`pair`, :func:`sealed`, :func:`decrypted`, :func:`kept`), and the runs of the learner's
``cryptography.sh`` as the submission (:func:`run_script`, through ``s.start_program``) with what they made
(:func:`script_made`, :func:`script_makes_key`).

:func:`tool` calls ``subprocess.run`` itself: the session's ``s.start_program`` runs a learner program as the
submission, with no standard input and its output as text, while age reads the plaintext from standard input
and writes binary ciphertext; ssh-keygen and age here are the grader's tools, run on files it copied.
"""

from __future__ import annotations

import glob
import os
import secrets
import shutil
import subprocess
import tempfile
from pathlib import Path

from ros2course.kit import Session, NotGradable, Unmet
from ros2course.kit.programs import ProgramRun, run_program
from ros2course.kit import learner_files as files

AGE_HEADERS = (b"age-encryption.org/v1\n", b"-----BEGIN AGE ENCRYPTED FILE-----")  # age(1): binary, or -a armored
#: nss_wrapper (cwrap.org, Debian/Ubuntu package libnss-wrapper): an LD_PRELOAD library that answers
#: getpwuid() from a passwd file named in NSS_WRAPPER_PASSWD; ssh-keygen(1) exits with "No user exists
#: for uid" without a passwd entry, and a class grade runs the script as a fresh uid that has none.
NSS_WRAPPER_GLOBS = ("/usr/lib/*-linux-gnu/libnss_wrapper.so*", "/usr/lib64/libnss_wrapper.so*",
                     "/usr/lib/libnss_wrapper.so*", "/usr/local/lib/libnss_wrapper.so*")
NO_PASSWD = 97  # the wrapper's exit code: no passwd entry and no nss_wrapper to lend one
#: Runs the learner's script (``{script}``: its path from the run's folder); lends its uid a passwd entry (in the
#: run's own folder) only when it has none.
SCRIPT_WRAPPER = """if ! getent passwd "$(id -u)" > /dev/null; then
  [ -n "$NSS_WRAPPER_LIB" ] || exit {no_passwd}
  printf 'learner:x:%s:%s:learner:%s:/bin/sh\\n' "$(id -u)" "$(id -g)" "$PWD" > .nss-passwd
  printf 'learner:x:%s:\\n' "$(id -g)" > .nss-group
  export LD_PRELOAD="$NSS_WRAPPER_LIB" NSS_WRAPPER_PASSWD="$PWD/.nss-passwd" NSS_WRAPPER_GROUP="$PWD/.nss-group"
fi
unset NSS_WRAPPER_LIB
exec bash {script}
"""

#: A judgement: check id -> (passed, observed).
Found = dict[str, tuple[bool, str]]


def require_tools() -> None:
    """Raises:
        NotGradable: ``age`` or ``ssh-keygen`` is not on this machine's PATH.
    """
    missing = [name for name in ("age", "ssh-keygen") if shutil.which(name) is None]
    if missing:
        raise NotGradable(f"the cryptography lesson is graded with the age and ssh-keygen commands, and "
                          f"{' and '.join(missing)} is not on this machine's PATH",
                          "sudo apt install age openssh-client (Ubuntu 24.04), then check again")


def crypto_folder(s: Session, check_id: str, folder: str) -> Path:
    """``check_id``: ``folder`` is a folder (not a link) in the workspace; returns its resolved path.

    Raises:
        Unmet: it is not.
    """
    path = s.workspace_root / folder
    if path.is_symlink() or not path.is_dir():
        s.record(check_id, False, f"there is no folder {folder}/ in {s.workspace_root}", "a folder crypto/")
        raise Unmet(f"no {folder}/")
    s.record(check_id, True, f"{folder}/ exists", "a folder crypto/")
    return Path(os.path.realpath(path))


def record(s: Session, names: dict[str, str], found: Found) -> None:
    """Record each judgement of ``found``, expecting what the check's name (``names``: id -> name) says."""
    for check_id, (passed, observed) in found.items():
        s.record(check_id, passed, observed, names[check_id])


def tool(name: str, *args: str, data: bytes | None = None) -> subprocess.CompletedProcess:
    """Run the system's ``age`` or ``ssh-keygen`` on files (never a program of the submission), ``data`` (bytes)
    on its standard input, its output captured as bytes.

    Raises:
        subprocess.TimeoutExpired: it ran longer than 20 seconds.
    """
    return subprocess.run([shutil.which(name) or name, *args], input=data, capture_output=True, timeout=20)


def said(run: subprocess.CompletedProcess | None) -> str:
    """The first line a tool printed (age's and ssh-keygen's error line comes first), for feedback."""
    lines = [] if run is None else (run.stderr or run.stdout).decode("utf-8", "replace").strip().splitlines()
    return lines[0][:160] if lines else "nothing"


def private(src: Path, tmp: Path) -> Path:
    """A copy of ``src`` (its first ``files.MAX_READ`` bytes) with mode 600 in the grader's folder ``tmp``
    (ssh-keygen ignores a readable key of one's own)."""
    handle, copy = tempfile.mkstemp(dir=tmp)  # mode 600
    with os.fdopen(handle, "wb") as out, src.open("rb") as given:
        out.write(given.read(files.MAX_READ))
    return Path(copy)


def pair(key: Path, pub: Path, tmp: Path) -> Found:
    """private_key, private_mode, ed25519, public_matches, own_key_decrypts for the private ``key`` and its
    public ``pub`` (copies in ``tmp``); a later entry is meaningless when an earlier fails (only private_key
    when ssh-keygen cannot read the key)."""
    copy = private(key, tmp)
    derived = tool("ssh-keygen", "-y", "-P", "", "-f", str(copy))
    if derived.returncode != 0:
        return {"private_key": (False, f"ssh-keygen -y -P '' -f {key.name} failed: {said(derived)}")}
    mode = key.stat().st_mode & 0o777
    listed = tool("ssh-keygen", "-l", "-f", str(copy)).stdout.decode("utf-8", "replace").strip()
    shown = files.read_text(pub).strip() if pub.is_file() and not pub.is_symlink() else ""
    # type and base64 key; the comment after them is free text (ssh-keygen(1), -C)
    ours, theirs = derived.stdout.decode("utf-8", "replace").split()[:2], shown.split()[:2]
    nonce = secrets.token_hex(16).encode()
    locked = tool("age", "-R", str(private(pub, tmp)), data=nonce) if ours == theirs else None
    opened = tool("age", "-d", "-i", str(copy), data=locked.stdout) if locked and locked.returncode == 0 else None
    return {
        "private_key": (True, f"ssh-keygen -y reads {key.name}: {ours[0]} key, no passphrase"),
        # exactly 600, the lesson's mode (400 or 700 keep others out too, but the lesson and its title say 600,
        # and script_keeps_key asks the same of the script's key: helper audit of issue 37)
        "private_mode": (mode == 0o600, f"{key.name} has mode {mode:o}"),
        "ed25519": (listed.endswith("(ED25519)"), f"ssh-keygen -l -f {key.name}: {listed or 'nothing'}"),
        "public_matches": (ours == theirs, f"{pub.name} holds {' '.join(theirs)[:60] or 'nothing'}...; ssh-keygen -y "
                                           f"derives {' '.join(ours)[:60]}... from {key.name}"),
        "own_key_decrypts": (opened is not None and opened.stdout == nonce,
                             "age -d -i my_key returned the nonce encrypted to my_key.pub" if opened and
                             opened.stdout == nonce else f"age could not round-trip a nonce: {said(opened or locked)}"),
    }


def sealed(path: Path, key: Path, message: str) -> Found:
    """age_format, instructor_decrypts: ``path`` starts with an age header and the shipped private ``key`` (a
    private copy) decrypts it to a non-empty text of the learner's own: not the shipped ``message`` (a copy of the
    shipped ``.age``, or the decrypted secret encrypted again: the lesson's "a short text of your own"; audit of
    stop 71). Only age_format when the header is wrong."""
    head = path.read_bytes()[:40]
    if not head.startswith(AGE_HEADERS):
        return {"age_format": (False, f"{path.name} starts with {head[:30]!r}, not an age header")}
    opened = tool("age", "-d", "-i", str(key), str(path))
    text = opened.stdout.decode("utf-8", "replace").strip()
    theirs = bool(text) and text == message.strip()
    return {"age_format": (True, f"{path.name} starts with {head.splitlines()[0][:40]!r}"),
            "instructor_decrypts": (opened.returncode == 0 and bool(text) and not theirs,
                                    f"age -d -i exercise_ed25519 failed: {said(opened)}" if opened.returncode else
                                    f"the shipped key decrypts it to {text[:60]!r}" + (
                                        ": that is the instructor's own message, not a text of yours" if theirs
                                        else ""))}


def decrypted(path: Path, message: str) -> tuple[bool, str]:
    """The file's text against the shipped message (its final newline optional); the answer is not quoted."""
    text, same = files.read_text(path), files.read_text(path).rstrip("\n") == message.rstrip("\n")
    return same, f"{path.name} holds {text[:80]!r}" + ("" if same else f", not the {len(message.strip())} "
                                                       "characters the shipped key decrypts the message to")


#: What opens a private key file: OpenSSH's (ssh-keygen's default) and PEM's (``-m PEM``, openssl, PKCS#8).
PRIVATE_KEY_MARKERS = (b"-----BEGIN OPENSSH PRIVATE KEY-----", b"PRIVATE KEY-----")
#: colcon's output folders and version control: not the learner's packages.
NOT_PACKAGES = {"build", "install", "log", ".git"}


def keys_in_packages(src: Path, most: int = 20000) -> tuple[list[str], int]:
    """The files under ``src`` (the workspace's packages) that hold a private key: their paths relative to
    ``src``'s parent, and how many files were looked at. A file counts when one of
    :data:`PRIVATE_KEY_MARKERS` is in its first 4 KiB and it is at most 64 KiB (a key is about 400 bytes);
    links are never followed; colcon's build/, install/, log/ and .git are left out; at most ``most`` files
    are looked at (a workspace of many packages)."""
    found: list[str] = []
    looked = 0
    for here, dirs, names in os.walk(src, followlinks=False):
        dirs[:] = sorted(d for d in dirs if d not in NOT_PACKAGES)
        for name in sorted(names):
            path = Path(here) / name
            if looked >= most:
                return found, looked
            looked += 1
            try:
                if path.is_symlink() or not path.is_file() or path.stat().st_size > 65536:
                    continue
                with path.open("rb") as handle:
                    head = handle.read(4096)
            except OSError:
                continue
            if any(marker in head for marker in PRIVATE_KEY_MARKERS):
                found.append(path.relative_to(src.parent).as_posix())
    return found, looked


def key_outside_src(root: Path) -> tuple[bool, str]:
    """The lesson: "a private key has no place in a ROS package (colcon installs it and you may publish it):
    keep it in crypto/, outside src/". Passes when no file of ``root``/src holds one (or there is no src/)."""
    src = root / "src"
    if not src.is_dir() or src.is_symlink():
        return True, "no src/ folder: no package holds a key"
    found, looked = keys_in_packages(src)
    if found:
        shown = ", ".join(found[:3]) + (f" and {len(found) - 3} more" if len(found) > 3 else "")
        return False, f"a private key in your packages: {shown}"
    return True, f"no private key among the {looked} files of src/"


def kept(made: Path, handed_in: dict[str, str]) -> Found:
    """Whether the script left the ``handed_in`` pair (file name -> text) in ``made`` as it was (same text, the
    key's mode 600); one entry per file name."""
    found = {}
    for name, text in handed_in.items():
        path, mode = made / name, (made / name).lstat().st_mode & 0o777 if (made / name).exists() else 0
        same, key = path.is_file() and not path.is_symlink() and files.read_text(path) == text, name == "my_key"
        found[name] = (same and (not key or mode == 0o600), f"after the script, {name} is " + (
            "as it was" if same else "gone or another file") + (f", mode {mode:o}" if key else ""))
    return found


def nss_wrapper() -> str:
    """The path of libnss_wrapper.so on this machine, or "" (then a uid without a passwd entry cannot make keys)."""
    found = sorted(path for pattern in NSS_WRAPPER_GLOBS for path in glob.glob(pattern))
    return found[0] if found else ""


def fill(folder: str, script_name: str, trusted: dict[str, Path], script: Path, handed_in: dict[str, str],
         where: Path, with_pair: bool = True) -> None:
    """Make ``where/folder``: the ``trusted`` shipped files (name -> the course's copy), the learner's ``script``
    as ``script_name`` and, ``with_pair``, the ``handed_in`` pair (name -> text), my_key at mode 600."""
    (where / folder).mkdir()
    for name, src in [*trusted.items(), (script_name, script)]:
        shutil.copyfile(src, where / folder / name)
    for name, text in handed_in.items() if with_pair else ():
        (where / folder / name).write_text(text, encoding="utf-8")
    if with_pair and "my_key" in handed_in:  # a workspace without my_key (the starter's) has none to protect
        (where / folder / "my_key").chmod(0o600)


def run_script(s: Session, where: Path, label: str, script: str) -> ProgramRun:
    """``bash <script>`` (``script``: its path from ``where``) in ``where`` as the submission (30 s at most),
    through SCRIPT_WRAPPER.

    Raises:
        NotGradable: the script's uid has no passwd entry (a class grade's sandbox) and this machine has
            no nss_wrapper to lend it one: ssh-keygen would refuse to run, whatever the script.
    """
    env = {**s.base_env, "NSS_WRAPPER_LIB": nss_wrapper()}
    wrapper = SCRIPT_WRAPPER.format(no_passwd=NO_PASSWD, script=script)
    # stdin a pipe nobody writes to: a question (ssh-keygen without -N asks for a passphrase) waits, as in a
    # terminal, instead of reading an empty answer from /dev/null
    run = run_program(s, ["bash", "-c", wrapper], label, timeout=30.0, cwd=where, env=env, stdin_open=True)
    if run.returncode == NO_PASSWD and not run.stdout and not run.stderr:
        raise NotGradable("the script runs as a uid with no passwd entry, for which ssh-keygen refuses to work, "
                          "and this machine has no nss_wrapper library to lend it one",
                          "apt install libnss-wrapper (Debian, Ubuntu), then grade again")
    return run


def script_made(s: Session, names: dict[str, str], where: Path, folder: str, script: str,
                message: str, key: Path, handed_in: dict[str, str]) -> None:
    """script_runs, then script_decrypts, script_keeps_key, script_encrypts: run ``folder/script`` in ``where``
    (filled with the ``handed_in`` pair, name -> text) and judge what it made as the files were judged (``message``: the
    shipped message; ``key``: a private copy of the shipped key). ``names``: check id -> name (the expected)."""
    run = run_script(s, where, "cryptography-script", f"{folder}/{script}")
    last = run.stderr.strip().splitlines()[-1:]
    s.record("script_runs", run.returncode == 0 and not run.timed_out, f"bash {folder}/{script}: {run.describe()}"
             + "".join(f", last output: {line[:120]}" for line in last), names["script_runs"])
    made, judges = where / folder, {  # the same judgements as above, of the files the script made
        "script_decrypts": ("decrypted_message.txt", lambda path: {"decrypted": decrypted(path, message)}),
        "script_keeps_key": ("my_key", lambda path: kept(made, handed_in)),
        "script_encrypts": ("message_to_instructor.txt.age", lambda path: sealed(path, key, message))}
    for check_id, (name, judge) in judges.items():
        path = made / name
        found = judge(path) if path.is_file() and not path.is_symlink() else {
            check_id: (False, f"after the script ran, crypto/ holds no file {name}")}
        failed = [observed for passed, observed in found.values() if not passed]
        s.record(check_id, not failed, "; ".join(failed or [o for _, o in found.values()]), names[check_id])


def script_makes_key(s: Session, names: dict[str, str], fresh: Path, folder: str, script: str,
                     tmp: Path) -> None:
    """script_makes_key: run ``folder/script`` in ``fresh`` (filled without my_key): step 2 of the script must
    make the pair (no question asked), judged as the handed-in pair is (:func:`pair`, copies in ``tmp``)."""
    second = run_script(s, fresh, "cryptography-script-no-key", f"{folder}/{script}")
    key, pub = fresh / folder / "my_key", fresh / folder / "my_key.pub"
    minted = pair(key, pub, tmp) if key.is_file() and not key.is_symlink() else {
        "private_key": (False, "crypto/my_key is missing")}
    failed = [observed for passed, observed in minted.values() if not passed]
    if second.returncode != 0 or second.timed_out:
        failed.insert(0, f"bash {folder}/{script} without my_key: {second.describe()}" + "".join(
            f", last output: {line[:120]}" for line in second.stderr.strip().splitlines()[-1:]))
    s.record("script_makes_key", not failed, "with no my_key, the script: " + "; ".join(
        failed or [observed for _, observed in minted.values()]), names["script_makes_key"])
