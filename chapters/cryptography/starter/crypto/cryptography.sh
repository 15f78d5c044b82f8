#!/usr/bin/env bash
# Lesson cryptography: write every step of the lesson here, so that
#     bash crypto/cryptography.sh
# run from any folder redoes them in crypto/. The grader runs this script in a
# fresh copy of crypto/ (holding only the three exercise_* files and this
# script) and checks what it makes there; it must not ask any question.
set -euo pipefail
cd "$(dirname "$0")"

# TODO 1: decrypt exercise_message.txt.age with the private key exercise_ed25519
#         and save the text in decrypted_message.txt (age -d -i ... > ...)

# TODO 2: if my_key does not exist yet, make an ed25519 key pair my_key / my_key.pub
#         with ssh-keygen, with an empty passphrase (-N "") so nothing is asked

# TODO 3: encrypt a message of your own to the public key exercise_ed25519.pub
#         and save it in message_to_instructor.txt.age (echo "..." | age -R ... > ...)
