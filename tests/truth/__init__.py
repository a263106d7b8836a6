"""Tests of the truth simulators (casflutter.truth) and the problems listing."""
