"""The paper study: its statements and checks, figures, animations, report, `reproduce`."""
