from emogen.cli.app import app

app()
