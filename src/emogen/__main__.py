from emogen.cli import app

app()
