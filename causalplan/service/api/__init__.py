"""The JSON API: every ``/v1`` route (``routes/<resource>.py``) with its request and response schemas."""
