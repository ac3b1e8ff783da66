"""Example scenarios shipped with rocas (package data)."""
