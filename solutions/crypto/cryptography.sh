#!/usr/bin/env bash
# Lesson cryptography: every step of the lesson, from any folder: bash crypto/cryptography.sh
set -euo pipefail
cd "$(dirname "$0")"

# 1. Decrypt the shipped message with the shipped private key.
age -d -i exercise_ed25519 exercise_message.txt.age > decrypted_message.txt

# 2. Make my own ed25519 key pair without a passphrase, once (an existing key is never overwritten).
if [ ! -f my_key ]; then
    ssh-keygen -t ed25519 -N "" -f my_key
fi

# 3. Encrypt a message to the instructor's public key.
echo "Dear instructor, this secret was sealed with age for your key only." \
    | age -R exercise_ed25519.pub > message_to_instructor.txt.age
