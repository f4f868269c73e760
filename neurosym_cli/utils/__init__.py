"""Small shared helpers: device, seeding, console."""
