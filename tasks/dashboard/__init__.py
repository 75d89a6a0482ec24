"""What the dashboard shows, read from the store: one read-model module per page group (plain dataclasses a page
renders and its JSON twin returns), the files it serves by artifact id, and pictures it makes on request. Nothing
here writes to the store."""
