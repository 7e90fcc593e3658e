"""References for impact scenes, written without importing wavecontact (see docs/impact.md)."""
