"""The floor motion estimators."""
