"""The traffic's reaction to an edit: refinement written back into the draft, and the room search."""
