"""The private course's graders: the public ones with hidden checks added."""
