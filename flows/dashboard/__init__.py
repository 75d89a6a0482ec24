"""``simsplat dashboard``: a read-only web app over the store (FastAPI, server-rendered Jinja templates, every asset
served by the app itself). ``app.create_app`` builds it; one module per page group in ``pages/`` (each page with
a JSON twin under ``/api``); what the pages show is read by ``tasks.dashboard``."""
