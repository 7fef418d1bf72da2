"""Gymnasium-Robotics' Fetch tasks with factors of variation (extra ``robotics``): see :mod:`.env`.

Importing this package imports nothing heavy; :mod:`.env` needs ``gymnasium_robotics`` (its models)
and ``mujoco``.
"""
