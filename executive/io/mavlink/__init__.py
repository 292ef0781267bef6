"""MAVLink: link, reader, commander and the executive's own heartbeat (pymavlink)."""
