"""The device the suite tests (pytest's --device option, set by conftest.py): the tests marked
`gpu` take it from the `device` fixture and render there; `make gpu-check` runs them with
--device cuda."""

NAME = "cpu"
