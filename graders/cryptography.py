"""Grader for ``cryptography`` (the seed author's Jazzy edition, Cybersecurity: public-key cryptosystems).

The chapter makes an ed25519 pair with ``ssh-keygen``, encrypts with ``age -R key.pub``, decrypts with
``age -d -i key``; its exercises decrypt the shipped ``exercise_message.txt.age`` with ``exercise_ed25519``
and encrypt a message to ``exercise_ed25519.pub``. The grader runs the system's ``age`` and ``ssh-keygen``
on private copies of the files in ``crypto/`` (never a learner program, except ``cryptography.sh``, run as
the submission in a fresh folder); the shipped key it trusts is the lesson's starter copy, not the learner's.
Rules: ssh-keygen(1) (``-y`` derives the public key, ``-l`` names the type, ``-P ""`` the empty passphrase;
a private key others may read is refused); age(1) (a file starts ``age-encryption.org/v1`` or is armored
with ``-a``; ``-R`` takes ssh-ed25519 recipients; ``-d -i`` decrypts with an SSH private key).
"""

from __future__ import annotations

import glob
import os
import secrets
import shutil
import subprocess
import tempfile
from pathlib import Path

from ros2course.kit import Check, GradingSession, NotGradable, Unmet
from ros2course.kit.programs import ProgramRun, run_program
from . import _files as files

WINDOW = 0.0  # no ROS program is observed
FOLDER, SCRIPT = "crypto", "cryptography.sh"
AGE_HEADERS = (b"age-encryption.org/v1\n", b"-----BEGIN AGE ENCRYPTED FILE-----")  # age(1): binary, or -a armored
SHIPPED = ("exercise_ed25519", "exercise_ed25519.pub", "exercise_message.txt.age")
#: nss_wrapper (cwrap.org, Debian/Ubuntu package libnss-wrapper): an LD_PRELOAD library that answers
#: getpwuid() from a passwd file named in NSS_WRAPPER_PASSWD; ssh-keygen(1) exits with "No user exists
#: for uid" without a passwd entry, and a class grade runs the script as a fresh uid that has none.
NSS_WRAPPER_GLOBS = ("/usr/lib/*-linux-gnu/libnss_wrapper.so*", "/usr/lib64/libnss_wrapper.so*",
                     "/usr/lib/libnss_wrapper.so*", "/usr/local/lib/libnss_wrapper.so*")
NO_PASSWD = 97  # the wrapper's exit code: no passwd entry and no nss_wrapper to lend one
#: Runs the learner's script; lends its uid a passwd entry (in the run's own folder) only when it has none.
SCRIPT_WRAPPER = f"""if ! getent passwd "$(id -u)" > /dev/null; then
  [ -n "$NSS_WRAPPER_LIB" ] || exit {NO_PASSWD}
  printf 'learner:x:%s:%s:learner:%s:/bin/sh\\n' "$(id -u)" "$(id -g)" "$PWD" > .nss-passwd
  printf 'learner:x:%s:\\n' "$(id -g)" > .nss-group
  export LD_PRELOAD="$NSS_WRAPPER_LIB" NSS_WRAPPER_PASSWD="$PWD/.nss-passwd" NSS_WRAPPER_GROUP="$PWD/.nss-group"
fi
unset NSS_WRAPPER_LIB
exec bash {FOLDER}/{SCRIPT}
"""

K = ("private_key",)  # the key part's checks and the script (run with the learner's pair) need the key
CHECKS = [
    Check("crypto_folder", "crypto/ is a folder in the workspace", 1, "keep the lesson's files in crypto/"),
    Check("decrypted", "crypto/decrypted_message.txt is the shipped message, decrypted", 2,
          "age -d -i exercise_ed25519 exercise_message.txt.age > decrypted_message.txt", ("crypto_folder",), "decrypt"),
    Check("private_key", "crypto/my_key is an OpenSSH private key without a passphrase", 1,
          "ssh-keygen -t ed25519 -f my_key, Enter twice for no passphrase", needs=("crypto_folder",), part="keys"),
    Check("private_mode", "crypto/my_key has mode 600 (only its owner may read it)", 1, "chmod 600 my_key", K, "keys"),
    Check("ed25519", "ssh-keygen -l says my_key is an ED25519 key", 1, "make it with ssh-keygen -t ed25519", K, "keys"),
    Check("public_matches", "crypto/my_key.pub is my_key's public key", 1,
          "keep the files ssh-keygen wrote together (ssh-keygen -y -f my_key > my_key.pub remakes it)", K, "keys"),
    Check("own_key_decrypts", "A message age encrypts to my_key.pub decrypts with my_key", 1,
          "age -R my_key.pub ... then age -d -i my_key ...", needs=("ed25519", "public_matches"), part="keys"),
    Check("age_format", "crypto/message_to_instructor.txt.age is an age file", 1,
          "age -R exercise_ed25519.pub message.txt > message_to_instructor.txt.age", ("crypto_folder",), "encrypt"),
    Check("instructor_decrypts", "The shipped private key decrypts it to a non-empty message", 2,
          "encrypt to the instructor's exercise_ed25519.pub, not to your own my_key.pub", ("age_format",), "encrypt"),
    Check("script_runs", "bash crypto/cryptography.sh runs to exit code 0 in a fresh folder", 1,
          "run it yourself in a fresh copy: it must neither ask anything nor fail", K, "script"),
    Check("script_decrypts", "The script writes decrypted_message.txt, the decrypted message", 1,
          "the script runs age -d -i exercise_ed25519 ... > decrypted_message.txt", ("script_runs",), "script"),
    Check("script_keeps_key", "The script leaves an existing my_key and my_key.pub as they were, mode 600", 1,
          "the script runs ssh-keygen only if my_key is missing: if [ ! -f my_key ]; then ...", ("script_runs",), "script"),
    Check("script_encrypts", "The script writes message_to_instructor.txt.age for the shipped key", 1,
          "the script pipes a message into age -R exercise_ed25519.pub > message_to_instructor.txt.age",
          needs=("script_runs",), part="script"),
    Check("script_makes_key", "Where my_key is missing, the script makes an ed25519 pair, no passphrase, mode 600", 2,
          "the script runs ssh-keygen -t ed25519 -N \"\" -f my_key when my_key is missing: nothing may ask",
          needs=("script_runs",), part="script"),
]


def _tool(name: str, *args: str, data: bytes | None = None) -> subprocess.CompletedProcess:
    """Run the system's ``age`` or ``ssh-keygen`` on files (never a program of the submission)."""
    return subprocess.run([shutil.which(name) or name, *args], input=data, capture_output=True, timeout=20)


def _said(run: subprocess.CompletedProcess | None) -> str:
    """The first line a tool printed (age's and ssh-keygen's error line comes first), for feedback."""
    lines = [] if run is None else (run.stderr or run.stdout).decode("utf-8", "replace").strip().splitlines()
    return lines[0][:160] if lines else "nothing"


def _private(src: Path, tmp: Path) -> Path:
    """A copy of ``src`` with mode 600 in the grader's folder (ssh-keygen ignores a readable key of one's own)."""
    handle, copy = tempfile.mkstemp(dir=tmp)  # mode 600
    with os.fdopen(handle, "wb") as out, src.open("rb") as given:
        out.write(given.read(files.MAX_READ))
    return Path(copy)


def _pair(key: Path, pub: Path, tmp: Path) -> dict[str, tuple[bool, str]]:
    """The key checks' ``(passed, observed)``; a later entry is meaningless when an earlier fails."""
    copy = _private(key, tmp)
    derived = _tool("ssh-keygen", "-y", "-P", "", "-f", str(copy))
    if derived.returncode != 0:
        return {"private_key": (False, f"ssh-keygen -y -P '' -f {key.name} failed: {_said(derived)}")}
    mode = key.stat().st_mode & 0o777
    listed = _tool("ssh-keygen", "-l", "-f", str(copy)).stdout.decode("utf-8", "replace").strip()
    shown = files.read_text(pub).strip() if pub.is_file() and not pub.is_symlink() else ""
    # type and base64 key; the comment after them is free text (ssh-keygen(1), -C)
    ours, theirs = derived.stdout.decode("utf-8", "replace").split()[:2], shown.split()[:2]
    nonce = secrets.token_hex(16).encode()
    sealed = _tool("age", "-R", str(_private(pub, tmp)), data=nonce) if ours == theirs else None
    opened = _tool("age", "-d", "-i", str(copy), data=sealed.stdout) if sealed and sealed.returncode == 0 else None
    return {
        "private_key": (True, f"ssh-keygen -y reads {key.name}: {ours[0]} key, no passphrase"),
        "private_mode": (mode & 0o077 == 0 and mode & 0o400 != 0, f"{key.name} has mode {mode:o}"),
        "ed25519": (listed.endswith("(ED25519)"), f"ssh-keygen -l -f {key.name}: {listed or 'nothing'}"),
        "public_matches": (ours == theirs, f"{pub.name} holds {' '.join(theirs)[:60] or 'nothing'}...; ssh-keygen -y "
                                           f"derives {' '.join(ours)[:60]}... from {key.name}"),
        "own_key_decrypts": (opened is not None and opened.stdout == nonce,
                             "age -d -i my_key returned the nonce encrypted to my_key.pub" if opened and
                             opened.stdout == nonce else f"age could not round-trip a nonce: {_said(opened or sealed)}"),
    }


def _sealed(path: Path, key: Path) -> dict[str, tuple[bool, str]]:
    head = path.read_bytes()[:40]
    if not head.startswith(AGE_HEADERS):
        return {"age_format": (False, f"{path.name} starts with {head[:30]!r}, not an age header")}
    opened = _tool("age", "-d", "-i", str(key), str(path))
    text = opened.stdout.decode("utf-8", "replace").strip()
    return {"age_format": (True, f"{path.name} starts with {head.splitlines()[0][:40]!r}"),
            "instructor_decrypts": (opened.returncode == 0 and bool(text),
                                    f"the shipped key decrypts it to {text[:60]!r}" if opened.returncode == 0
                                    else f"age -d -i exercise_ed25519 failed: {_said(opened)}")}


def _decrypted(path: Path, message: str) -> tuple[bool, str]:
    """The file's text against the shipped message (its final newline optional); the answer is not quoted."""
    text, same = files.read_text(path), files.read_text(path).rstrip("\n") == message.rstrip("\n")
    return same, f"{path.name} holds {text[:80]!r}" + ("" if same else f", not the {len(message.strip())} "
                                                       "characters the shipped key decrypts the message to")


def _kept(made: Path, pair: dict[str, str]) -> dict[str, tuple[bool, str]]:
    """Whether the script left the handed-in pair as it was (same text, the key's mode 600)."""
    found = {}
    for name, text in pair.items():
        path, mode = made / name, (made / name).lstat().st_mode & 0o777 if (made / name).exists() else 0
        same, key = path.is_file() and not path.is_symlink() and files.read_text(path) == text, name == "my_key"
        found[name] = (same and (not key or mode == 0o600), f"after the script, {name} is " + (
            "as it was" if same else "gone or another file") + (f", mode {mode:o}" if key else ""))
    return found


def _nss_wrapper() -> str:
    """The path of libnss_wrapper.so on this machine, or "" (then a uid without a passwd entry cannot make keys)."""
    found = sorted(path for pattern in NSS_WRAPPER_GLOBS for path in glob.glob(pattern))
    return found[0] if found else ""


def _run_script(s: GradingSession, where: Path, label: str) -> ProgramRun:
    """``bash crypto/cryptography.sh`` in ``where`` as the submission (30 s at most), through SCRIPT_WRAPPER.

    Raises:
        NotGradable: the script's uid has no passwd entry (a class grade's sandbox) and this machine has
            no nss_wrapper to lend it one: ssh-keygen would refuse to run, whatever the script.
    """
    env = {**s.base_env, "NSS_WRAPPER_LIB": _nss_wrapper()}
    run = run_program(s, ["bash", "-c", SCRIPT_WRAPPER], label, timeout=30.0, cwd=where, env=env)
    if run.returncode == NO_PASSWD and not run.stdout and not run.stderr:
        raise NotGradable("the script runs as a uid with no passwd entry, for which ssh-keygen refuses to work, "
                          "and this machine has no nss_wrapper library to lend it one",
                          "apt install libnss-wrapper (Debian, Ubuntu), then grade again")
    return run


def grade(s: GradingSession) -> None:
    """Judge crypto/'s files, then run the learner's script in a fresh folder and judge what it made."""
    missing = [name for name in ("age", "ssh-keygen") if shutil.which(name) is None]
    if missing:
        raise NotGradable(f"the cryptography lesson is graded with the age and ssh-keygen commands, and "
                          f"{' and '.join(missing)} is not on this machine's PATH",
                          "sudo apt install age openssh-client (Ubuntu 24.04), then check again")
    folder = s.workspace_root / FOLDER
    if folder.is_symlink() or not folder.is_dir():
        s.record("crypto_folder", False, f"there is no folder {FOLDER}/ in {s.workspace_root}", "a folder crypto/")
        raise Unmet(f"no {FOLDER}/")
    s.record("crypto_folder", True, f"{FOLDER}/ exists", "a folder crypto/")
    real, tmp = Path(os.path.realpath(folder)), Path(tempfile.mkdtemp(dir=s.log_dir, prefix="grader-keys-"))
    trusted = {name: s.lesson.starter_dir / FOLDER / name for name in SHIPPED}  # the course's, not the learner's
    key = _private(trusted["exercise_ed25519"], tmp)
    message = _tool("age", "-d", "-i", str(key), str(trusted["exercise_message.txt.age"])).stdout.decode()
    checks = {c.id: c for c in CHECKS}

    def record(found: dict[str, tuple[bool, str]]) -> None:
        for check_id, (passed, observed) in found.items():
            s.record(check_id, passed, observed, checks[check_id].name)

    with s.part("decrypt"):
        path = files.entry(s, "decrypted", real / "decrypted_message.txt", real, checks["decrypted"].name)
        record({"decrypted": _decrypted(path, message)})
    with s.part("keys"):
        record(_pair(files.entry(s, "private_key", real / "my_key", real, "crypto/my_key"), real / "my_key.pub", tmp))
    with s.part("encrypt"):
        age_file = files.entry(s, "age_format", real / "message_to_instructor.txt.age", real, checks["age_format"].name)
        record(_sealed(age_file, key))
    with s.part("script"):
        script = files.entry(s, "script_runs", real / SCRIPT, real, f"crypto/{SCRIPT}")

        pair = {name: files.read_text(real / name) for name in ("my_key", "my_key.pub") if (real / name).is_file()}

        def fill(where: Path, with_pair: bool = True) -> None:  # the shipped files, the script (and the pair)
            (where / FOLDER).mkdir()
            for name, src in [*trusted.items(), (SCRIPT, script)]:
                shutil.copyfile(src, where / FOLDER / name)
            for name, text in pair.items() if with_pair else ():
                (where / FOLDER / name).write_text(text, encoding="utf-8")
            if with_pair:
                (where / FOLDER / "my_key").chmod(0o600)
        where = s.submission_folder("script-run", fill)
        run = _run_script(s, where, "cryptography-script")
        said = run.stderr.strip().splitlines()[-1:]
        s.record("script_runs", run.returncode == 0 and not run.timed_out, f"bash {FOLDER}/{SCRIPT}: {run.describe()}"
                 + "".join(f", last output: {line[:120]}" for line in said), checks["script_runs"].name)
        made, judges = where / FOLDER, {  # the same judgements as above, of the files the script made
            "script_decrypts": ("decrypted_message.txt", lambda path: {"decrypted": _decrypted(path, message)}),
            "script_keeps_key": ("my_key", lambda path: _kept(made, pair)),
            "script_encrypts": ("message_to_instructor.txt.age", lambda path: _sealed(path, key))}
        for check_id, (name, judge) in judges.items():
            path = made / name
            found = judge(path) if path.is_file() and not path.is_symlink() else {
                check_id: (False, f"after the script ran, crypto/ holds no file {name}")}
            failed = [observed for passed, observed in found.values() if not passed]
            s.record(check_id, not failed, "; ".join(failed or [o for _, o in found.values()]), checks[check_id].name)
        # a second fresh folder without the pair: step 2 of the script must make it (no question asked)
        fresh = s.submission_folder("script-run-no-key", lambda where: fill(where, with_pair=False))
        second = _run_script(s, fresh, "cryptography-script-no-key")
        key, pub = fresh / FOLDER / "my_key", fresh / FOLDER / "my_key.pub"
        minted = _pair(key, pub, tmp) if key.is_file() and not key.is_symlink() else {
            "private_key": (False, "crypto/my_key is missing")}
        failed = [observed for passed, observed in minted.values() if not passed]
        if second.returncode != 0 or second.timed_out:
            failed.insert(0, f"bash {FOLDER}/{SCRIPT} without my_key: {second.describe()}" + "".join(
                f", last output: {line[:120]}" for line in second.stderr.strip().splitlines()[-1:]))
        s.record("script_makes_key", not failed, "with no my_key, the script: " + "; ".join(
            failed or [observed for _, observed in minted.values()]), checks["script_makes_key"].name)
