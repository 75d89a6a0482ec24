"""The offline English -> ``EditProgram`` parser: ``prompt.parse_prompt`` and the rules it reads prompts with."""
