"""Test-only embodichain plugin (installed into the test environment)."""
