"""Grader for ``cryptography`` (the seed author's Jazzy edition, Cybersecurity: public-key cryptosystems).

The chapter makes an ed25519 pair with ``ssh-keygen``, encrypts with ``age -R key.pub``, decrypts with
``age -d -i key``; its exercises decrypt the shipped ``exercise_message.txt.age`` with ``exercise_ed25519``
and encrypt a message to ``exercise_ed25519.pub``. The grader runs the system's ``age`` and ``ssh-keygen``
on private copies of the files in ``crypto/`` (never a learner program, except ``cryptography.sh``, run as
the submission in a fresh folder); the shipped key it trusts is the lesson's starter copy, not the learner's.
Rules: ssh-keygen(1) (``-y`` derives the public key, ``-l`` names the type, ``-P ""`` the empty passphrase;
a private key others may read is refused); age(1) (a file starts ``age-encryption.org/v1`` or is armored
with ``-a``; ``-R`` takes ssh-ed25519 recipients; ``-d -i`` decrypts with an SSH private key).
The judgements, the grader's runs of age and ssh-keygen and the script's runs are in graders/_cryptography.py;
this module declares the checks and their order.
"""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path

from ros2course.kit import Check, Session
from . import _cryptography as crypto
from ros2course.kit import learner_files as files

WINDOW = 0.0  # no ROS program is observed
FOLDER, SCRIPT = "crypto", "cryptography.sh"
SHIPPED = ("exercise_ed25519", "exercise_ed25519.pub", "exercise_message.txt.age")

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
    Check("key_outside_src", "No private key in the workspace's packages (src/)", 1,
          "a package is installed and published: keep private keys in crypto/ only, and delete the copy in src/"),
]


def grade(s: Session) -> None:
    """Judge crypto/'s files, then run the learner's script in a fresh folder and judge what it made."""
    crypto.require_tools()
    real = crypto.crypto_folder(s, "crypto_folder", FOLDER)
    tmp = Path(tempfile.mkdtemp(dir=s.log_dir, prefix="grader-keys-"))
    trusted = {name: s.lesson.starter_dir / FOLDER / name for name in SHIPPED}  # the course's, not the learner's
    key = crypto.private(trusted["exercise_ed25519"], tmp)
    message = crypto.tool("age", "-d", "-i", str(key), str(trusted["exercise_message.txt.age"])).stdout.decode()
    names = {c.id: c.name for c in CHECKS}
    with s.part("decrypt"):
        path = files.entry(s, "decrypted", real / "decrypted_message.txt", real, names["decrypted"])
        crypto.record(s, names, {"decrypted": crypto.decrypted(path, message)})
    with s.part("keys"):
        my_key = files.entry(s, "private_key", real / "my_key", real, "crypto/my_key")
        crypto.record(s, names, crypto.pair(my_key, real / "my_key.pub", tmp))
    with s.part("encrypt"):
        age_file = files.entry(s, "age_format", real / "message_to_instructor.txt.age", real, names["age_format"])
        crypto.record(s, names, crypto.sealed(age_file, key, message))
    with s.part("script"):
        script = files.entry(s, "script_runs", real / SCRIPT, real, f"crypto/{SCRIPT}")
        pair = {name: files.read_text(real / name) for name in ("my_key", "my_key.pub") if (real / name).is_file()}
        fill = functools.partial(crypto.fill, FOLDER, SCRIPT, trusted, script, pair)
        crypto.script_made(s, names, s.submission_folder("script-run", fill), FOLDER, SCRIPT, message, key, pair)
        # a second fresh folder without the pair: step 2 of the script must make it (no question asked)
        fresh = s.submission_folder("script-run-no-key", functools.partial(fill, with_pair=False))
        crypto.script_makes_key(s, names, fresh, FOLDER, SCRIPT, tmp)
    s.record("key_outside_src", *crypto.key_outside_src(s.workspace_root),
             "no file under src/ holding a private key (the lesson: keep them in crypto/, outside src/)")
