"""Reading and writing frames, videos, benchmark sequences and box files."""
