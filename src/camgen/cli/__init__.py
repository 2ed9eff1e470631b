"""Command-line interface: one module per subcommand; each parses, loads, calls the library, reports."""
