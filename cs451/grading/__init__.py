"""The autograder: tests declared per stage, run against a submission in a subprocess, reported."""
