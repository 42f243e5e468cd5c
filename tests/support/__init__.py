"""Helpers the tests share: building a database, reading USD back, motions with known answers."""
