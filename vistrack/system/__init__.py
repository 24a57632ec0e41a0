"""The process: memory and disk budgets (:mod:`.resources`), signals (:mod:`.signals`) and the compile
notice (:mod:`.compiling`)."""
